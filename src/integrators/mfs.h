// `mfs`: Tessendorf's multiple forward scattering (seed eq. 3 / corrected eq. 17, steady state) as a
// march along the camera ray. The derivations, numbered D1 .. D16, are in docs/derivations.md; the
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
// Near a medium's side the scattered light's direction is tilted towards the medium, as the camera-side
// peak-scattered paths that stay in it are (camera_tilt, D16); in the bulk, the lights' first wide
// scatter is read in the direction tilted along the beam's gradient (camera_shift, D17). Where the
// footprint leaves through the face the ray entered by, its scattered light is lost (entry_loss, D18).
// Camera-side light is attenuated by the reduced extinction (times the 1 / cosh path lengthening, D5,
// with path_lengthening, or the camera-side beam's fluence factor, D19, with camera_fluence).
// forward_side "light" (D11) instead spreads everything on the light's side and takes the camera leg
// exactly. Light transmittances come from deep shadow maps (deterministic); the
// environment is carried by the scatter grid from its entry. Every channel uses its own optical depths;
// overlapping media share one tau_p (sum of f_i sigma_s_i).
//
// Options (the JSON fields of the scene's integrator block besides type, spp, seed, max_events; the
// settings struct's fields carry the same names; docs/scene-format.md says more):
//
// | field                     | type                          | default   | meaning                               |
// |---------------------------|-------------------------------|-----------|---------------------------------------|
// | `tau_step`                | number in [1e-4, 100]         | 0.4       | optical depth per march step (against the majorant) |
// | `step_growth`             | number in [0, 100]            | 3         | steps of tau_step (1 + step_growth tau_red), tau_red the camera-side reduced depth; fixed steps of min(tau_step, 0.1) in the majorant cells where a medium may emit; on constant-density spheres and boxes each step is also at most two node spacings of the photon grids (docs/derivations.md D13) |
// | `light_path`              | "forward" or "beer_lambert"   | "forward" | the light reaches the first wide scatter through peak scatters (reduced extinction), or unscattered only (the seed paper) |
// | `propagator`              | "gsa" or "gaussian"           | "gsa"     | the peak's own moments in the small-angle propagator, or a Gaussian stand-in with the same theta2 |
// | `peak_fraction`           | "auto" or [0, 0.99]           | "auto"    | f, the part of each phase function carried as a forward peak ("auto": min(chi_2, g) per medium, g^2 for HG) |
// | `large_angle_scatters`    | "all" or integer in [0, 1024] | "all"     | K, at most K wide scatters per path (0: the peak only; 1: the seed's picture) |
// | `photons`                 | "auto" or integer in [1, 2^26] | "auto"   | scatter grid photons per pass, shared among the lights (80 % by power, 20 % evenly) ("auto": 2^18 up to 128 x 128 pixels, then 2^18 sqrt(pixels / 128^2), half that where the camera looks into a directional or point light's forward peak, times clamp(sqrt(3.4 / C), 1/2, 4) for C real and null collisions per photon of a pilot (ScatterGridSettings::adaptive_photons), at most 2^26; the header of a rendered image holds the number chosen) |
// | `photon_transport`        | "exact" or "similarity"       | "exact"   | scatter grid photons in the true medium, or in the delta-scaled one |
// | `channel_passes`          | boolean                       | false     | chromatic media: one scatter grid photon pass per colour channel (each with its own coefficients) instead of one pass of hero-channel photons carrying all three (scatter_grid.h) |
// | `scatter_grid_resolution` | "auto" or integer in [4, 96]  | "auto"    | scatter and beam grid nodes along the longest axis ("auto": ~1.6 optical depths per cell, 32 to 64, from 512 x 512 pixels on; 3/4 of that up to 128 x 128; the header of a rendered image holds the number chosen) |
// | `scatter_grid_bands`      | "auto" or integer in [1, 6]   | "auto"    | spherical-harmonic bands the grid keeps and reads (l < bands; "auto": 1 where every medium scatters isotropically without a peak, else 3) |
// | `grid_lobe_tail`          | boolean                       | true      | with 3 bands, the wide scatter of the grid's light also takes its l = 3..5 moments, extrapolated from a lobe about its l = 1 direction (ScatterGridSettings::lobe_tail) |
// | `grid_denoise`            | boolean                       | true      | the scatter grid's nodes inside the media filtered where their difference from their neighbours is photon noise, by the photon batches' spread (grid_denoise.h) |
// | `forward_side`            | "camera" or "light"           | "camera"  | peak scatters after the last wide scatter carried to the camera, or taken on the light's side with an exact camera leg |
// | `beam_photons`            | "auto" or integer in [0, 2^24] | "auto"  | photons per light for the peak-only beam grid, shared among the channels' passes in chromatic media (0: straight beams; "auto": 2^13 sqrt(pixels / 128^2), at most 2^15, and 2^15 sqrt(pixels / 128^2), at most 8 x 2^15, for a light whose forward peak the camera looks into, and for every light in thin media (the scatter grid pilot's collisions per photon below 1.2), and none where no medium has a peak: auto_beam_photons in mfs_settings.cpp) |
// | `beam_spread`             | "straight" or "traced"        | "straight" | the peak-only light's angular spread: the straight beam's peak depth ln(T_wide / T_light) (D8), or the beam grid's photons' mean cosine read against the straight beam's (D9b; backlit spheres' binned error 1.4x, docs/benchmarks.md "The beam's spread") |
// | `beam_smoothing`          | integer in [0, 8]             | 2         | passes of the filter [1 2 1] / 4 along each axis over the beam grid's nodes inside the media (0: none): the grid's noise averaged over about one node spacing (BeamGrid) |
// | `photon_splat`            | "trilinear", "stochastic" or "stratified" | "trilinear" | how the scatter grid's photons deposit each track sample: over the 8 nodes around it, or whole to one of them drawn by its trilinear weight (independently, or stratified along the track); the same expected grid, more noise (the beam grid stays trilinear) |
// | `light_blur`              | boolean                       | true      | the first wide scatter sees the beam's light-side angular spread |
// | `path_lengthening`        | boolean                       | false     | the corrected kernel's 1 / cosh loss on paths lengthened by peak deflections (replaces camera_fluence) |
// | `camera_fluence`          | boolean                       | false     | the light scattered towards the camera carried by the camera-side peak beam's fluence, not its flux: its deflected paths gather more of the medium per unit depth and lose more to sigma_red (D19; the half-space's answer, not the default: docs/benchmarks.md) |
// | `filtered_lookups`        | boolean                       | false     | scatter grid read pre-filtered over the camera-side lateral spread |
// | `source_blur`             | boolean                       | false     | the source (sigma_s times every scattered term) read at a point drawn from the camera-side lateral footprint (D10), so rays near a boundary gather partly outside the medium |
// | `camera_tilt`             | boolean                       | true      | near a medium's side, the camera-bound light's direction is tilted towards the medium, as the peak-scattered paths that stayed in it are (D16; ignored with source_blur, forward_side "light" and light_path "beer_lambert") |
// | `camera_shift`            | boolean                       | true      | in the bulk (both footprint points in a medium), the lights' first wide scatter read in the direction tilted towards each light by cov(offset, deflection) sigma_red: the correlation of the footprint's offset with its deflection along the beam's gradient (D17), the beam's growth cut at the medium's surface towards the light (D17b; with camera_tilt only) |
// | `entry_loss`              | boolean                       | true      | where a footprint offset of a march step (with camera_tilt) lies outside the media before the entry of the line through it along the ray (the camera-bound paths displaced there left through the face the ray came in by, and no light beyond the ray's chord makes up for them), the scattered light of that half of the footprint is lost (D18) |
// | `peak_toward_camera`      | boolean                       | false     | the forward peak alone takes its angular factor from the beam grid's photons (their P_peak towards the camera) instead of peak_eff at the beam's mean-cosine depth (one medium only) |
// | `wide_toward_camera`      | boolean                       | false     | the lights' first wide scatter takes its angular factor from the beam grid's photons: P_wide from their directions towards the camera, over the straight beam's wide_eff at the same samples, multiplies the straight factor (D20; one medium only) |
// | `exact_light_transmittance` | "auto" or boolean           | "auto"    | T_light and T_wide to directional and point lights without the shadow maps: the chord in closed form for one constant-density sphere or box, else a march ("auto": true for one constant-density sphere or box, else false; the header of a rendered image holds the choice) |
// | `shadow_map_resolution`   | integer in [8, 1024]          | 64        | deep shadow map nodes along the longest axis |
// | `edge_samples`            | "auto" or integer in [1, 64]  | "auto"    | samples per pixel sample at pixels a hard outline crosses (constant-density spheres and boxes, surfaces: scene/edges.h), a quarter of it (at least 1) beside them; 1: none; "auto": where the camera looks into a directional or point light's forward peak 64 up to 128 x 128 pixels, 64 / sqrt(pixels / 128^2) above, at least 16 (auto_edge_samples), else 16 (docs/benchmarks.md "Samples at the outlines") |
//
// forward_side "light" needs light_path "forward" and photon_transport "exact": the other values are
// errors naming both fields.
#pragma once

#include <algorithm>
#include <memory>
#include <optional>
#include <vector>

#include "integrators/beam_grid.h"
#include "integrators/integrator.h"
#include "integrators/mfs_estimators.h"
#include "integrators/scatter_grid.h"
#include "integrators/shadow_map.h"
#include "scene/lights.h"
#include "transport/phase_split.h"

namespace nimbus {

enum class LightPath { forward, beer_lambert };
enum class Propagator { gsa, gaussian };
enum class PhotonTransport { exact, similarity };
enum class ForwardSide { camera, light };
enum class BeamSpread { straight, traced };

// The camera march's step in the majorant cells where a medium may emit: at most this optical depth (and
// tau_step where that is finer). The emission's spatial variation is not blurred by the propagator, so it
// needs the steps the old default of tau_step (0.1) gave it (docs/benchmarks.md, issue 12).
inline constexpr double kEmissionStep = 0.1;

struct MfsSettings {
  double tau_step = 0.4;
  double step_growth = 3.0;
  LightPath light_path = LightPath::forward;
  Propagator propagator = Propagator::gsa;
  std::optional<double> peak_fraction;      // nullopt: "auto"
  std::optional<int> large_angle_scatters;  // nullopt: "all"
  std::optional<int> photons;               // nullopt: "auto" (resolved by MfsIntegrator: image size, pilot)
  PhotonTransport photon_transport = PhotonTransport::exact;
  bool channel_passes = false;
  std::optional<int> scatter_grid_resolution;  // nullopt: "auto" (resolved by MfsIntegrator)
  std::optional<int>
      scatter_grid_bands;  // nullopt: "auto" (resolved by MfsIntegrator: auto_scatter_grid_bands)
  ForwardSide forward_side = ForwardSide::camera;
  std::optional<int>
      beam_photons;  // nullopt: "auto" (resolved per light by MfsIntegrator: auto_beam_photons)
  BeamSpread beam_spread = BeamSpread::straight;
  int beam_smoothing = 2;
  Splat photon_splat = Splat::trilinear;
  bool light_blur = true;
  bool path_lengthening = false;
  bool camera_fluence = false;
  bool filtered_lookups = false;
  bool source_blur = false;
  bool camera_tilt = true;
  bool camera_shift = true;
  bool entry_loss = true;
  bool grid_denoise = true;
  bool grid_lobe_tail = true;
  bool peak_toward_camera = false;
  bool wide_toward_camera = false;
  std::optional<bool> exact_light_transmittance;  // nullopt: "auto" (resolved by MfsIntegrator)
  int shadow_map_resolution = 64;
  std::optional<int> edge_samples;  // nullopt: "auto" (resolved by MfsIntegrator: auto_edge_samples)

  bool forward_light_path() const { return light_path == LightPath::forward; }
  bool light_side() const { return forward_side == ForwardSide::light; }
};

// The integrator block's own fields (strict: unknown keys and conflicting fields are errors naming
// `where` and the JSON paths), and back.
MfsSettings mfs_settings_from_json(const nlohmann::json& options, const std::string& where);
nlohmann::json to_json(const MfsSettings& s);

// March steps taken by this thread's `mfs` camera rays (all of them, gathered rays included): one
// increment per step, read by bench/bench_mfs_pixel.cpp for steps per ray; no effect on any image.
inline thread_local uint64_t mfs_march_steps = 0;

class MfsIntegrator final : public Integrator {
 public:
  // seed: the scene's, for the photon grids.
  MfsIntegrator(const SceneContext& context, MfsSettings settings, uint64_t seed = 1);
  Rgb Li(const Ray& ray, Rng& rng, CameraSample* sample = nullptr) const override;
  // Li with `bounces` more rays gathered at the surface the ray ends on (Li: 1).
  Rgb trace(const Ray& ray, Rng& rng, CameraSample* sample, int bounces) const;
  // The settings with "auto" resolved (scatter_grid_resolution).
  nlohmann::json settings_json() const override { return to_json(s_); }
  int edge_samples() const override { return s_.edge_samples.value_or(16); }
  const PhaseSplit& split(int medium) const { return *splits_[medium]; }
  const ScatterGrid* scatter_grid() const { return grid_.get(); }
  const BeamGrid* beam_grid() const { return beam_.get(); }
  // The longest step of the march over analytic pieces (constant-density shapes): the grids' node spacing.
  double max_step() const { return max_step_; }
  // Bytes held by the deep shadow maps and the scatter grid.
  size_t memory_bytes() const;

 private:
  const SceneContext& ctx_;
  MfsSettings s_;
  std::vector<std::unique_ptr<PhaseSplit>> splits_;  // per medium
  std::vector<double> f_;                            // per medium peak fraction
  std::vector<double> theta2_;                       // per medium peak's mean square angle
  std::vector<double> drift_;                        // per medium 1 - chi_1 of its peak (eq. D19; empty: off)
  std::vector<TransmittanceGrid> full_maps_, reduced_maps_;  // per light
  std::unique_ptr<ScatterGrid> grid_;                        // wide scatters 2 .. K (null for K = 1)
  std::vector<int> grid_moments_;   // per medium: a grid lookup's chi_l, l < this (tail_moments in mfs.cpp)
  std::unique_ptr<BeamGrid> beam_;  // the peak-only beams' correction (or null)
  std::vector<int> beam_counts_;    // per light: the beam grid's photons
  double max_step_ = 0.0;           // the longest march step over analytic pieces (the grids' node spacing)
  bool shared_stencil_ = false;     // both photon grids, on one node layout: one stencil per march point
  // The beam grid is built: the forward light path and photons for some light.
  bool beam_on() const {
    return s_.forward_light_path() &&
           std::any_of(beam_counts_.begin(), beam_counts_.end(), [](int n) { return n > 0; });
  }

  // The parts of `Li` (mfs.cpp); the physics is in mfs_estimators.h.
  struct MediumRadiance {
    Rgb L;         // per unit sigma_s_i, reaching the camera through CameraPoint::T_cam
    Rgb L_peak;    // the forward-peak-only paths (light_path "forward"), through CameraPoint::T_full
    Rgb L_lights;  // the part of L straight from the lights (no scatter grid): the `direct` layer
  };
  // What the media at m (evaluated at p) send towards the camera, summed over the media and weighted by
  // sigma_s_i: the parts through T_cam (scattered) and the forward peak through T_full (peak).
  struct Sources {
    Rgb in_scatter{0.0}, peak_scatter{0.0}, lights_scatter{0.0};
  };
  // d: the camera ray's direction (the forward peak alone leaves along -d); d_s: the direction whose
  // reverse the scattered light (T_cam) leaves along (d, or camera_tilt's, eq. D16); y_out: Y_lm(-d_s),
  // the scatter grid's basis towards the camera. y.tau_p is the scattered light's camera-side peak depth.
  // The photon grids' trilinear stencil at p is found once for both where they share a layout (st: null
  // where each finds its own).
  void add_sources(const MediumPoint& m, const Vec3& p, const Vec3& d, const Vec3& d_s, const ShBasis& y_out,
                   double t, const CameraPoint& y, const CameraPath& cam, Rng& rng, bool scattered, bool peak,
                   Sources* out) const;
  // Every source of one march step at p (eq. D7's sum): on the ray, or with source_blur (D14) or
  // camera_tilt (D16).
  // probe: the ray's camera_tilt offsets (null without camera_tilt).
  Sources step_sources(const MediumPoint& m, const Vec3& p, const Vec3& d, const ShBasis& y_out, double t,
                       const CameraPoint& y, const CameraPath& cam, Rng& rng, FootprintProbe* probe) const;
  // camera_tilt's offsets for a ray along d (eq. D16; nullopt without camera_tilt, with source_blur, with
  // forward_side "light" and with light_path "beer_lambert").
  std::optional<FootprintProbe> footprint_probe(const Vec3& d, Rng& rng) const;
  // camera_tilt (eq. D16): whether exactly one of p +- u (u the probe's next point of the lateral footprint
  // of depth t) is in a medium; then d_s, the tilted direction, and residual, the share of tau_p left to
  // the spread. With camera_shift (eq. D17), also where both are (the bulk): then *bulk is set (and d_s,
  // residual are not). With entry_loss (eq. D18), *kept gets the share of the scattered light whose
  // footprint half did not leave through the face the ray entered by (1, 0.5 or 0; left as it is where
  // both points are in a medium).
  bool tilt(const Vec3& p, const Vec3& d, double t, const CameraPath& cam, FootprintProbe& probe, Vec3* d_s,
            double* residual, bool* bulk, double* kept) const;
  // eq. D18: whether the line through q (a point outside the media) along d meets a medium ahead of q
  // before one behind it, within 4 r either way: q lies before that line's entry into the media.
  bool before_entry(const Vec3& q, const Vec3& d, double r) const;
  // source_blur (eq. D14): T_cam's light read at a point of the lateral footprint around p, zero outside
  // the media (the forward peak alone stays on the ray: add_sources at p).
  void add_blurred_sources(const Vec3& p, const Vec3& d, const ShBasis& y_out, double t, const CameraPoint& y,
                           const CameraPath& cam, Rng& rng, Sources* out) const;
  // What medium i sends towards the camera from the sample point p (at distance t) of the march: one
  // sample of every light (eqs. D7, D11) and the scatter grid's higher orders (eq. D12).
  MediumRadiance medium_radiance(int i, const Vec3& p, const Vec3& d, const Vec3& d_s, const ShBasis& y_out,
                                 double t, const CameraPoint& y, const CameraPath& cam, Rng& rng,
                                 const TrilinearStencil* st) const;
  // Light l's peak-only beam at p for medium i: shadow maps, beam grid (eqs. D8, D9); an area light
  // marches to its sampled point ls instead of reading a map.
  LightBeam light_beam(size_t l, int i, const Vec3& p, const LightSample& ls,
                       const TrilinearStencil* st) const;
  // exact_light_transmittance: T_light and T_wide from p to the light sample without the shadow maps (a
  // closed-form chord for one analytic medium, else a march).
  void exact_light_transmittance(const Vec3& p, const LightSample& ls, Rgb* T_light, Rgb* T_wide) const;
  // The shadow maps per light: the full and the reduced one (only the reduced one, for the beam grid,
  // with exact_light_transmittance).
  void build_maps();
  // The beam grid over the photons' splits and tracking majorants (with the camera tallies its options ask for).
  void build_beam(const std::vector<const PhaseSplit*>& splits, const MajorantGrid* tracking, uint64_t seed);
  // The beam from the environment image along wi (marched: full and reduced transmittance, no beam grid).
  LightBeam environment_beam(int i, const Vec3& p, const Vec3& wi) const;
  // The scatter grid's light, taking its last wide scatter at p towards the camera (eq. D12).
  Rgb higher_orders(int i, const Vec3& p, const ShBasis& y_out, double t, const Rgb& tau_p,
                    const CameraPath& cam, const TrilinearStencil* st) const;
};

}  // namespace nimbus
