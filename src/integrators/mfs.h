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
//
// Options (the JSON fields of the scene's integrator block besides type, spp, seed, max_events; the
// settings struct's fields carry the same names; docs/scene-format.md says more):
//
// | field                     | type                          | default   | meaning                               |
// |---------------------------|-------------------------------|-----------|---------------------------------------|
// | `tau_step`                | number in [1e-4, 100]         | 0.1       | optical depth per march step (against the majorant) |
// | `step_growth`             | number in [0, 100]            | 1         | steps of tau_step (1 + step_growth tau_red), tau_red the camera-side reduced depth |
// | `light_path`              | "forward" or "beer_lambert"   | "forward" | the light reaches the first wide scatter through peak scatters (reduced extinction), or unscattered only (the seed paper) |
// | `propagator`              | "gsa" or "gaussian"           | "gsa"     | the peak's own moments in the small-angle propagator, or a Gaussian stand-in with the same theta2 |
// | `peak_fraction`           | "auto" or [0, 0.99]           | "auto"    | f, the part of each phase function carried as a forward peak ("auto": g^2 per medium) |
// | `large_angle_scatters`    | "all" or integer in [0, 1024] | "all"     | K, at most K wide scatters per path (0: the peak only; 1: the seed's picture) |
// | `photons`                 | integer in [1, 2^26]          | 262144    | scatter grid photons per channel pass, shared among the lights |
// | `photon_transport`        | "exact" or "similarity"       | "exact"   | scatter grid photons in the true medium, or in the delta-scaled one |
// | `scatter_grid_resolution` | "auto" or integer in [4, 96]  | "auto"    | scatter and beam grid nodes along the longest axis ("auto": ~1.6 optical depths per cell, 32 to 64; the header of a rendered image holds the number chosen) |
// | `scatter_grid_bands`      | integer in [1, 3]             | 3         | spherical-harmonic bands used at lookup (l < bands) |
// | `forward_side`            | "camera" or "light"           | "camera"  | peak scatters after the last wide scatter carried to the camera, or taken on the light's side with an exact camera leg |
// | `beam_photons`            | integer in [0, 2^24]          | 32768     | photons per light for the peak-only beam grid (0: straight beams) |
// | `light_blur`              | boolean                       | true      | the first wide scatter sees the beam's light-side angular spread |
// | `path_lengthening`        | boolean                       | false     | the corrected kernel's 1 / cosh loss on paths lengthened by peak deflections |
// | `filtered_lookups`        | boolean                       | false     | scatter grid read pre-filtered over the camera-side lateral spread |
// | `shadow_map_resolution`   | integer in [8, 1024]          | 64        | deep shadow map nodes along the longest axis |
//
// forward_side "light" needs light_path "forward" and photon_transport "exact": the other values are
// errors naming both fields.
#pragma once

#include <memory>
#include <optional>
#include <vector>

#include "integrators/beam_grid.h"
#include "integrators/integrator.h"
#include "integrators/scatter_grid.h"
#include "integrators/shadow_map.h"
#include "scene/lights.h"
#include "transport/phase_split.h"

namespace nimbus {

enum class LightPath { forward, beer_lambert };
enum class Propagator { gsa, gaussian };
enum class PhotonTransport { exact, similarity };
enum class ForwardSide { camera, light };

struct MfsSettings {
  double tau_step = 0.1;
  double step_growth = 1.0;
  LightPath light_path = LightPath::forward;
  Propagator propagator = Propagator::gsa;
  std::optional<double> peak_fraction;        // nullopt: "auto"
  std::optional<int> large_angle_scatters;    // nullopt: "all"
  int photons = 1 << 18;
  PhotonTransport photon_transport = PhotonTransport::exact;
  std::optional<int> scatter_grid_resolution;  // nullopt: "auto" (resolved by MfsIntegrator)
  int scatter_grid_bands = 3;
  ForwardSide forward_side = ForwardSide::camera;
  int beam_photons = 1 << 15;
  bool light_blur = true;
  bool path_lengthening = false;
  bool filtered_lookups = false;
  int shadow_map_resolution = 64;

  bool forward_light_path() const { return light_path == LightPath::forward; }
  bool light_side() const { return forward_side == ForwardSide::light; }
};

// The integrator block's own fields (strict: unknown keys and conflicting fields are errors naming
// `where` and the JSON paths), and back.
MfsSettings mfs_settings_from_json(const nlohmann::json& options, const std::string& where);
nlohmann::json to_json(const MfsSettings& s);

class MfsIntegrator final : public Integrator {
 public:
  // seed: the scene's, for the photon grids.
  MfsIntegrator(const SceneContext& context, MfsSettings settings, uint64_t seed = 1);
  Rgb Li(const Ray& ray, Rng& rng) const override { return radiance(ray.o, ray.d, rng); }
  // The settings with "auto" resolved (scatter_grid_resolution).
  nlohmann::json settings_json() const override { return to_json(s_); }
  const MfsSettings& settings() const { return s_; }
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
