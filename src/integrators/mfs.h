// `mfs`: one large-angle scatter carried to the camera by the multiple-forward-scattering propagator
// (seed eq. 3 / corrected eq. 17, steady state; design in docs/validation/render.md).
//
// Each medium's phase function is split P = f P_peak + (1 - f) P_wide (transport/phase_split.h). Peak
// scatters are small deflections carried by the generalised small-angle propagator; wide scatters are
// discrete events. Along the camera ray (march fixed in optical depth, jittered once per camera ray,
// as `single`) a point y at camera-side peak depth tau_p and reduced optical depth
// tau_r = int (sigma_a + (1 - f) sigma_s) receives light and sends towards the camera
//     sigma_s E_light [ (1 - f) T_light'(y) P_wide_eff(tau_p, mu) + f T_light(y) P_peak_eff(tau_p, mu) ]
//     exp(-tau_r)
// with mu the cosine between the light's and the camera-bound propagation directions:
//  - the wide term: the FIRST wide scatter of the path happens at y; light_path "forward" lets the light
//    reach y through peak scatters only (T_light' with the reduced extinction; the beam's angular spread on the
//    light side blurs P_wide_eff further: its peak depth adds to tau_p, option light_blur), "beer_lambert"
//    (paper-faithful) only unscattered (T_light = exp(-tau_t));
//    with beam_photons > 0 (default) T_light' is corrected by the photon-traced peak-only beam
//    (BeamGrid: lengthened paths, light leaving through the medium's sides) and the light-side angular
//    spread is the one with the beam's measured mean cosine;
//  - the peak term: paths with no wide scatter at all (the light seen through the forward peak: silver
//    linings), counted at their last peak scatter at y: the light's forward beam (its light-side
//    spread), then straight to the camera with the plain transmittance.
// Paths with two or more wide scatters (large_angle_scatters K > 1, default all): the light that has
// already scattered widely 1 .. K-1 times comes from a photon-traced fluence-and-flux grid
// (integrators/scatter_grid.h) and takes its last wide scatter at y:
//     sigma_s (1 - f) (phi + 3 g_wide_eff(tau_p) F . w_o) / (4 pi)
// with g_wide_eff = g_wide exp(-tau_p (1 - chi_1^peak)) (the camera-side peak blur of its mean cosine).
// Option filtered_lookups reads that grid pre-filtered (mip-mapped) over the lateral spread of the
// camera-side propagator, which grows with depth (seed sec. 1); the march's steps grow with the
// camera-side reduced depth (step_growth).
// Light transmittances come from deep shadow maps (deterministic). The environment (smooth in angle) is
// carried by the scatter grid from its entry, so the camera ray needs no environment sampling.
// Every channel uses its own optical depths; overlapping media share one tau_p (sum of f_i sigma_s_i).
#pragma once

#include <memory>
#include <vector>

#include "integrators/beam_grid.h"
#include "integrators/integrator.h"
#include "integrators/scatter_grid.h"
#include "integrators/shadow_map.h"
#include "render/lights.h"
#include "transport/phase_split.h"

namespace nimbus {

struct MfsSettings {
  double tau_step = 0.1;           // optical depth per march step (against the majorant)
  double step_growth = 1.0;        // steps of tau_step (1 + step_growth tau_red), tau_red: camera-side
  bool filtered_lookups = false;   // scatter grid looked up pre-filtered over the camera-side spread
  bool forward_light_path = true;  // light_path: "forward" (true) or "beer_lambert"
  bool gaussian = false;           // propagator: "gsa" (false) or "gaussian" (Gaussian stand-in for the peak)
  double peak_fraction = -1.0;     // f in [0, 0.99]; < 0: "auto" (g^2 per medium)
  bool path_lengthening = false;   // the 1 / cosh loss on paths lengthened by peak deflections
  int beam_photons = 1 << 15;      // per light, for the peak-only beam grid (BeamGrid); 0: straight beams
  bool light_blur = true;          // the first wide scatter sees the beam's light-side angular spread
  bool light_side = false;        // forward_side "light": peak scatters on the light's side, exact camera leg
  int large_angle_scatters = -1;  // K: at most K wide scatters per path (0: none, the peak only); -1 = "all"
  int shadow_map_resolution = 64;
  ScatterGridSettings grid;  // the higher orders (K != 1): photons, resolution; seed from the scene
};

MfsSettings parse_mfs_settings(const nlohmann::json& options, const std::string& where, bool strict,
                               uint64_t seed = 1);

class MfsIntegrator final : public Integrator {
 public:
  MfsIntegrator(const SceneContext& context, MfsSettings settings);
  Rgb sample(double px, double py, Rng& rng) const override;
  Rgb radiance(const Vec3& o, const Vec3& d, Rng& rng) const;
  const PhaseSplit& split(int medium) const { return *splits_[medium]; }
  const ScatterGrid* scatter_grid() const { return grid_.get(); }
  const BeamGrid* beam_grid() const { return beam_.get(); }
  // Bytes held by the deep shadow maps and the scatter grid.
  size_t memory_bytes() const;

 private:
  const SceneContext& ctx_;
  MfsSettings s_;
  std::vector<std::unique_ptr<PhaseSplit>> splits_;          // per medium
  std::vector<double> f_;                                    // per medium peak fraction
  std::vector<double> theta2_;                               // per medium peak's mean square angle
  std::vector<TransmittanceGrid> full_maps_, reduced_maps_;  // per light
  std::unique_ptr<ScatterGrid> grid_;                        // wide scatters 2 .. K (null for K = 1)
  std::unique_ptr<BeamGrid> beam_;                           // the peak-only beams' correction (or null)
};

}  // namespace nimbus
