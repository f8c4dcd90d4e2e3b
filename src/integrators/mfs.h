// `mfs`: Tessendorf's multiple forward scattering (seed eq. 3 / corrected eq. 17, steady state) as a
// march along the camera ray. The derivations, numbered D1 .. D13, are in docs/derivations.md; the
// estimators are free functions in integrators/mfs_estimators.h; design and accuracy in
// docs/validation/render.md.
//
// Each medium's phase function is split P = f P_peak + (1 - f) P_wide (D1, transport/phase_split.h).
// Peak scatters are small deflections carried by the generalised small-angle propagator (D3: they spread
// the light's direction without removing it, D2); wide scatters are discrete events. At each march point
// y (steps fixed in optical depth, jittered once per camera ray, growing with depth: D13) every medium
// sends towards the camera, per light sample:
//  - the FIRST wide scatter of the path (D7): the light reaches y through peak scatters only (T_wide,
//    the reduced shadow map, corrected by the photon-traced beam grid's R: D6, D9) spread by its
//    light-side peak depth, and is spread again on the camera side: wide_eff at the summed depths (D4);
//    light_path "beer_lambert" (paper-faithful) takes only unscattered light to y;
//  - the forward peak alone (D7): paths with no wide scatter, counted at their last peak scatter at y,
//    then straight to the camera with the plain transmittance (silver linings);
//  - with large_angle_scatters K > 1 (default all), the light that has already scattered widely, from a
//    photon-traced scatter grid (integrators/scatter_grid.h), by Funk-Hecke with the wide part's moments
//    blurred by the camera-side peak depth (D12), optionally pre-filtered over the camera-side lateral
//    spread (D10).
// Camera-side light is attenuated by the reduced extinction (times the 1 / cosh path lengthening, D5,
// with path_lengthening). forward_side "light" (D11) instead spreads everything on the light's side and
// takes the camera leg exactly. Light transmittances come from deep shadow maps (deterministic); the
// environment is carried by the scatter grid from its entry. Every channel uses its own optical depths;
// overlapping media share one tau_p (sum of f_i sigma_s_i).
#pragma once

#include <memory>
#include <vector>

#include "integrators/integrator.h"
#include "integrators/mfs_estimators.h"
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

  // The parts of `radiance` (mfs.cpp); the physics is in mfs_estimators.h.
  struct MediumRadiance {
    Rgb L;       // per unit sigma_s_i, reaching the camera through CameraPoint::T_cam
    Rgb L_peak;  // the forward-peak-only paths (light_path "forward"), through CameraPoint::T_full
  };
  // What medium i sends towards the camera from the sample point p (at distance t) of the march: one
  // sample of every light (eqs. D7, D11) and the scatter grid's higher orders (eq. D12).
  MediumRadiance medium_radiance(int i, const Vec3& p, const Vec3& d, double t, const CameraPoint& y,
                                 const CameraPath& cam, Rng& rng) const;
  // Light l's peak-only beam at p for medium i: shadow maps, beam grid (eqs. D8, D9).
  LightBeam light_beam(size_t l, int i, const Vec3& p) const;
  // The scatter grid's light, taking its last wide scatter at p towards the camera (eq. D12).
  Rgb higher_orders(int i, const Vec3& p, const Vec3& d, double t, const Rgb& tau_p,
                    const CameraPath& cam) const;
};

}  // namespace nimbus
