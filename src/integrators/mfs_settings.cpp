// `mfs`'s settings: its integrator block from JSON and back, and its "auto" choices (pure functions of
// the scene; the MfsIntegrator resolves them once).
#include "integrators/mfs_settings.h"

#include <algorithm>
#include <cmath>

#include "core/json_reader.h"
#include "media/density_grid.h"
#include "nimbus/error.h"

namespace nimbus {

namespace {
const std::vector<std::string> kLightPathNames = {"forward", "beer_lambert"};
const std::vector<std::string> kBeamSpreadNames = {"straight", "traced"};  // as BeamSpread
const std::vector<std::string> kPropagatorNames = {"gsa", "gaussian"};
const std::vector<std::string> kPhotonTransportNames = {"exact", "similarity"};
const std::vector<std::string> kForwardSideNames = {"camera", "light"};
const std::vector<std::string> kSplatNames = {"trilinear", "stochastic", "stratified"};  // as Splat
}  // namespace

MfsSettings mfs_settings_from_json(const nlohmann::json& options, const std::string& where) {
  MfsSettings s;
  JsonObject o(options, where, "/integrator");
  s.tau_step = o.number("tau_step", 1e-4, 100.0, s.tau_step);
  s.step_growth = o.number("step_growth", 0.0, 100.0, s.step_growth);
  s.light_path = LightPath(o.choice("light_path", kLightPathNames, int(s.light_path)));
  s.propagator = Propagator(o.choice("propagator", kPropagatorNames, int(s.propagator)));
  if (double f = 0.0; o.keyword_or_number("peak_fraction", "auto", 0.0, 0.99, &f)) s.peak_fraction = f;
  if (int64_t k = 0; o.keyword_or_integer("large_angle_scatters", "all", 0, 1024, &k))
    s.large_angle_scatters = int(k);
  if (int64_t n = 0; o.keyword_or_integer("photons", "auto", 1, 1 << 26, &n)) s.photons = int(n);
  s.photon_transport =
      PhotonTransport(o.choice("photon_transport", kPhotonTransportNames, int(s.photon_transport)));
  s.channel_passes = o.boolean("channel_passes", s.channel_passes);
  if (int64_t n = 0; o.keyword_or_integer("scatter_grid_resolution", "auto", 4, 96, &n))
    s.scatter_grid_resolution = int(n);
  if (int64_t n = 0; o.keyword_or_integer("scatter_grid_bands", "auto", 1, kShMaxBands, &n))
    s.scatter_grid_bands = int(n);
  s.forward_side = ForwardSide(o.choice("forward_side", kForwardSideNames, int(s.forward_side)));
  if (int64_t n = 0; o.keyword_or_integer("beam_photons", "auto", 0, 1 << 24, &n)) s.beam_photons = int(n);
  s.beam_spread = BeamSpread(o.choice("beam_spread", kBeamSpreadNames, int(s.beam_spread)));
  s.beam_smoothing = int(o.integer("beam_smoothing", 0, 8, s.beam_smoothing));
  s.photon_splat = Splat(o.choice("photon_splat", kSplatNames, int(s.photon_splat)));
  s.light_blur = o.boolean("light_blur", s.light_blur);
  s.path_lengthening = o.boolean("path_lengthening", s.path_lengthening);
  s.camera_fluence = o.boolean("camera_fluence", s.camera_fluence);
  s.filtered_lookups = o.boolean("filtered_lookups", s.filtered_lookups);
  s.source_blur = o.boolean("source_blur", s.source_blur);
  s.camera_tilt = o.boolean("camera_tilt", s.camera_tilt);
  s.camera_shift = o.boolean("camera_shift", s.camera_shift);
  s.entry_loss = o.boolean("entry_loss", s.entry_loss);
  s.grid_denoise = o.boolean("grid_denoise", s.grid_denoise);
  s.grid_lobe_tail = o.boolean("grid_lobe_tail", s.grid_lobe_tail);
  s.peak_toward_camera = o.boolean("peak_toward_camera", s.peak_toward_camera);
  s.wide_toward_camera = o.boolean("wide_toward_camera", s.wide_toward_camera);
  if (bool b = false; o.keyword_or_boolean("exact_light_transmittance", "auto", &b))
    s.exact_light_transmittance = b;
  s.shadow_map_resolution = int(o.integer("shadow_map_resolution", 8, 1024, s.shadow_map_resolution));
  if (int64_t n = 0; o.keyword_or_integer("edge_samples", "auto", 1, kMaxEdgeSamples, &n))
    s.edge_samples = int(n);
  o.finish();
  // The light side carries the light to every scatter through peak scatters, with photons in the true
  // medium: other choices would be silently overridden, so they are errors.
  if (s.light_side() && !s.forward_light_path())
    o.fail("light_path", "\"beer_lambert\" conflicts with " + o.path_of("forward_side") +
                             " \"light\" (the light side needs \"forward\")");
  if (s.light_side() && s.photon_transport != PhotonTransport::exact)
    o.fail("photon_transport", "\"similarity\" conflicts with " + o.path_of("forward_side") +
                                   " \"light\" (the light side needs \"exact\")");
  return s;
}

nlohmann::json to_json(const MfsSettings& s) {
  nlohmann::json j = {{"tau_step", s.tau_step},
                      {"step_growth", s.step_growth},
                      {"light_path", kLightPathNames[int(s.light_path)]},
                      {"propagator", kPropagatorNames[int(s.propagator)]},
                      {"photon_transport", kPhotonTransportNames[int(s.photon_transport)]},
                      {"channel_passes", s.channel_passes},
                      {"forward_side", kForwardSideNames[int(s.forward_side)]},
                      {"beam_spread", kBeamSpreadNames[int(s.beam_spread)]},
                      {"beam_smoothing", s.beam_smoothing},
                      {"photon_splat", kSplatNames[int(s.photon_splat)]},
                      {"light_blur", s.light_blur},
                      {"path_lengthening", s.path_lengthening},
                      {"camera_fluence", s.camera_fluence},
                      {"filtered_lookups", s.filtered_lookups},
                      {"source_blur", s.source_blur},
                      {"camera_tilt", s.camera_tilt},
                      {"camera_shift", s.camera_shift},
                      {"entry_loss", s.entry_loss},
                      {"grid_denoise", s.grid_denoise},
                      {"grid_lobe_tail", s.grid_lobe_tail},
                      {"peak_toward_camera", s.peak_toward_camera},
                      {"wide_toward_camera", s.wide_toward_camera},
                      {"shadow_map_resolution", s.shadow_map_resolution}};
  j["scatter_grid_bands"] =
      s.scatter_grid_bands ? nlohmann::json(*s.scatter_grid_bands) : nlohmann::json("auto");
  j["edge_samples"] = s.edge_samples ? nlohmann::json(*s.edge_samples) : nlohmann::json("auto");
  j["peak_fraction"] = s.peak_fraction ? nlohmann::json(*s.peak_fraction) : nlohmann::json("auto");
  j["large_angle_scatters"] =
      s.large_angle_scatters ? nlohmann::json(*s.large_angle_scatters) : nlohmann::json("all");
  j["photons"] = s.photons ? nlohmann::json(*s.photons) : nlohmann::json("auto");
  j["beam_photons"] = s.beam_photons ? nlohmann::json(*s.beam_photons) : nlohmann::json("auto");
  j["exact_light_transmittance"] =
      s.exact_light_transmittance ? nlohmann::json(*s.exact_light_transmittance) : nlohmann::json("auto");
  j["scatter_grid_resolution"] =
      s.scatter_grid_resolution ? nlohmann::json(*s.scatter_grid_resolution) : nlohmann::json("auto");
  return j;
}

// The photons' own majorant grid: the scene's cells with each cell's maximum taken from the voxels
// rather than from the 8^3 bricks' maxima. On the Disney cloud it cuts the photons' density lookups by
// 43 % (null collisions 73 % -> 53 % of them) for ~0.02 s of build (docs/benchmarks.md, issue 12). Any
// conservative majorant leaves delta tracking exact: the grids change only by photon noise. Its build
// reads every voxel ~3.4 times (~4 ns each) and saves ~5 lookups (~0.1 us each) per photon, so it is
// built only while the voxels are at most 16 per photon; else (and without grid media) nullopt: the
// photons track the scene's grid.
std::optional<MajorantGrid> photon_majorant_grid(const SceneContext& ctx, const MfsSettings& s,
                                                 const std::vector<int>& beam_counts) {
  double voxels = 0.0;
  for (int i = 0; i < ctx.media.count(); ++i) {
    const Shape& shape = ctx.media.medium(i).shape;
    const DensityGrid* g = nullptr;
    if (const auto* v = std::get_if<VdbShape>(&shape)) g = v->data.get();
    if (const auto* c = std::get_if<CloudShape>(&shape)) g = c->data.get();
    if (g) {
      const Vec3 e = g->index_hi() - g->index_lo();
      voxels += std::max(0.0, e.x) * std::max(0.0, e.y) * std::max(0.0, e.z);
    }
  }
  double photons = double(s.photons.value_or(0));
  for (size_t l = 0; l < beam_counts.size() && l < ctx.lights.size(); ++l)  // the beam grid traces these only
    if (std::holds_alternative<DirectionalLight>(ctx.lights[l]) ||
        std::holds_alternative<PointLight>(ctx.lights[l]))
      photons += double(beam_counts[l]);
  if (!(voxels > 0.0 && voxels <= 16.0 * photons)) return std::nullopt;
  const auto r = ctx.majorants.resolution();
  return std::optional<MajorantGrid>(std::in_place, ctx.media, std::max({r[0], r[1], r[2]}), false, true);
}

namespace {
// sqrt(pixels / 128^2), at least 1: how the photon grids' "auto" counts follow the whole image's size.
double pixel_scale(const PinholeCamera& camera) {
  const double pixels = double(camera.width()) * double(camera.height());
  return std::sqrt(std::max(1.0, pixels / (128.0 * 128.0)));
}
}  // namespace

// "auto" scatter-grid (and beam-grid) resolution: from 512 x 512 pixels on, cells of at most ~1.6 optical
// depths at the medium's typical extinction (the mean of the majorant grid's non-empty cells), 32 to 64
// nodes along the longest axis (32 up to an optical size of ~50 across); smaller images take that times
// 3/4 up to 128 x 128 pixels, 1/8 more per doubling of the width between (the full image's pixels, as
// auto_photons): 24 nodes for the small media at 128 x 128. A grid of spacing h blurs the photons' light
// by its deposit and lookup tents, a bias ~h^2 (the side-lit r = 10 sphere's mean with 2^22 photons:
// -2.2, -1.5, -1.0, -0.6 % at 24, 32, 48 and 96 nodes), and its noise variance goes as
// 1 / (photons h^3): the larger images' photons (auto_photons) buy a finer grid. Measured
// (docs/benchmarks.md, "The grids' resolution by image size"): at 128 x 128, 28 against 32 nodes gives
// 0.87x error^2 x CPU over the suite's spheres and box (10 seeds), 48 against 55 0.84x on the Disney
// cloud (6 seeds); at 512 x 512, 28 and 32 are the same and 40 is worse. With the scatter grid denoised
// (grid_denoise), 3/4 against 7/8 at 128 x 128 gives 0.79-0.95x error^2 x CPU on all nine suite scenes
// (6 seeds; docs/benchmarks.md, "The scatter grid denoised").
int auto_scatter_grid_resolution(const SceneContext& ctx) {
  const Bounds b = ctx.media.bounds();
  const Vec3 e = b.empty() ? Vec3(0.0) : b.hi - b.lo;
  const double across = std::max({e.x, e.y, e.z}) * ctx.majorants.mean_majorant();
  const double nodes = std::isfinite(across) ? std::clamp(std::ceil(across / 1.6), 32.0, 64.0) : 64.0;
  const double scale = std::min(1.0, (24.0 + 4.0 * std::log2(pixel_scale(ctx.camera))) / 32.0);
  return int(std::round(nodes * scale));
}

// "auto" scatter-grid bands. The camera side reads the grid's light through the wide part's moments chi_l
// (blurred by the peak, eq. D12; forward_side "light": the whole phase function's): where every medium's
// phase function is isotropic and carried without a peak (f = 0, as "auto" gives it), chi_l is 0 for
// l >= 1 and one band (the fluence) gives the same image, for a ninth of the floats per photon deposit (the
// isotropic Cycles-comparison spheres at 128 x 128: 0.78x and 0.80x the CPU with the beam grid off too,
// their errors unchanged; docs/benchmarks.md, "Isotropic media").
int auto_scatter_grid_bands(const std::vector<const PhaseSplit*>& splits) {
  constexpr double kZero = 1e-9;
  for (const PhaseSplit* split : splits) {
    if (split->f() > 0.0) return 3;
    const std::vector<double>& chi = split->wide_moments();
    for (size_t l = 1; l < 3 && l < chi.size(); ++l)
      if (std::abs(chi[l]) > kZero) return 3;
  }
  return 1;
}

namespace {
constexpr int kAutoBeamPhotons = 1 << 15;
// Whether the camera looks into a directional or point light's forward peak: the angle between the light's
// direction of travel (from a point light: towards the media's centre) and the direction from the media's
// centre to the camera is at most theta_c plus how far the directions from the media's visible points to the
// camera turn from that one: the angle the media's bounds subtend at the camera, at most the angle between the
// camera's axis and the media's centre plus half the image's diagonal; for a point light, plus the angle the
// bounds subtend at the light. A camera within the bounds' sphere may look anywhere: true.
bool camera_in_forward_peak(const SceneContext& ctx, const Light& light, double cut_angle) {
  const Bounds& b = ctx.media.bounds();
  if (b.empty() || !(cut_angle > 0.0)) return false;
  const auto* dir = std::get_if<DirectionalLight>(&light);
  const auto* point = std::get_if<PointLight>(&light);
  if (!dir && !point) return false;  // the beam grid traces directional and point lights only
  const Vec3 centre = (b.lo + b.hi) * 0.5;
  const double radius = 0.5 * (b.hi - b.lo).length();
  const auto angle = [](const Vec3& u, const Vec3& v) { return std::acos(std::clamp(dot(u, v), -1.0, 1.0)); };
  const PinholeCamera& cam = ctx.camera;
  const Vec3 to_camera = cam.origin() - centre;
  const double distance = to_camera.length();
  if (!(distance > radius)) return true;
  const Vec3 v = to_camera / distance, axis = cam.direction(0.5 * cam.width(), 0.5 * cam.height());
  const double half_diagonal = angle(cam.direction(0.0, 0.0), axis);
  double reach = cut_angle + std::min(std::asin(radius / distance), angle(-v, axis) + half_diagonal);
  Vec3 travel = dir ? normalize(dir->direction) : centre - point->position;
  if (point) {
    const double d = travel.length();
    if (!(d > radius)) return true;  // a light within the media sends its light every way
    reach += std::asin(radius / d);
    travel = travel / d;
  }
  return angle(travel, v) <= reach;
}

// Whether the camera looks into any light's forward peak (camera_in_forward_peak).
bool camera_in_any_forward_peak(const SceneContext& ctx, double cut_angle) {
  return std::any_of(ctx.lights.begin(), ctx.lights.end(),
                     [&](const Light& light) { return camera_in_forward_peak(ctx, light, cut_angle); });
}
}  // namespace

// "auto" scatter-grid photons: 2^18 up to 128 x 128 pixels, then 2^18 sqrt(pixels / 128^2), and half that where
// the camera looks into a directional or point light's forward peak. A grid of N photons costs c N of set-up and
// leaves a noise a / N in the error^2 beside mfs's bias b^2; the rest of the render costs F (the march, growing
// with the pixels). (b^2 + a / N) (F + c N) is least at N = sqrt(a F / (b^2 c)), so the count follows the square
// root of the pixels. Measured at 512 x 512 (docs/benchmarks.md, "Photons by image size"): 4 x 2^18 gives 0.70x
// error^2 x CPU on the Disney cloud and 0.56x on the front-lit r = 10 sphere against 2^18. Looking into the
// peak, the image is mostly the peak-carried light (the beam grid's) and the rim, and the wide light's noise a
// is a smaller part of it (docs/benchmarks.md, "Scatter photons where the camera looks into the peak"): 2^17 at
// 128 x 128 gives 0.76x error^2 x CPU on the backlit r = 10 sphere and 0.73x on the r = 20 one, 0.99x on the
// backlit chromatic box; 2^19 at 512 x 512 0.87x on the backlit r = 10 sphere. The full image's pixels, not the
// spp or a region's: a resumed, cropped or sample-range render traces the same photons as the render in one
// go. The scatter grid then multiplies this by a factor of its pilot's collisions per photon C,
// clamp(sqrt(3.4 / C), 1/2, 4) (ScatterGridSettings::adaptive_photons): a photon's cost c grows with C, and on
// thin media the grid's noise a is most of the error. The two factors of N multiply (docs/benchmarks.md,
// "Photons by collisions and image size together").
constexpr int kAutoPhotons = 1 << 18;
int auto_photons(const SceneContext& ctx, double cut_angle) {
  const double half = camera_in_any_forward_peak(ctx, cut_angle) ? 0.5 : 1.0;
  const double n = double(kAutoPhotons) * pixel_scale(ctx.camera) * half;
  return int(std::min(std::round(n), double(1 << 26)));
}

// "auto" beam-grid photons, per light: 2^13 sqrt(pixels / 128^2), at most 2^15, and 2^15 sqrt(pixels / 128^2)
// (at most 8 times 2^15) for a directional or point light whose forward peak the camera looks into
// (camera_in_forward_peak). The beam
// grid's noise reaches the image through the peak-only light (eq. D7, second term), which leaves a peak
// scatter within the cut angle theta_c of the light's direction of travel: it is most of a backlit medium's
// rim and next to nothing where the camera sees the light from the side. Measured at 512 x 512
// (docs/benchmarks.md, "Beam photons by image size", 2 seeds): 4 x 2^15 gives 0.68x error^2 x CPU on the
// backlit r = 10 sphere and 0.77x on the r = 20 one, but 1.06x on the side-lit r = 10 sphere and 1.07x on the
// double HG one (their error did not fall). The full image's pixels, as auto_photons.
// Thin media (`collisions`, the scatter grid pilot's real and null collisions per photon, below
// kThinCollisions) take the larger count for every light (the beam grid traces the directional and point ones;
// the others' count is one too, so that the header holds one number: a render resumed from it gives its
// photons, so it runs no pilot and could not resolve "auto" the same way): their beam photons are cheap
// and their noise is much of the error. At 512 x 512 (docs/benchmarks.md, "Beam
// photons in thin media"; 4 seeds) 4 x 2^15 gives 0.77x error^2 x CPU on the side-lit r = 1 sphere (C = 0.44)
// and 0.85x on the r = 2 one (0.89), but 1.08x on the side-lit r = 10 sphere (4.4) and 1.09x on the box (3.8),
// and 1.03x on the thin Disney cloud (0.82 real and 0.87 null collisions per photon: 1.69; its error did not
// move), which stays below the threshold; at 128 x 128 the count stays 2^15. Where no medium has a peak (an
// isotropic medium, f = 0): none. The lights of dense media seen from the side take 2^13 at 128 x 128: their
// beam grid is most of its cost fixed and its noise a small part of the error (docs/benchmarks.md, "Beam
// photons seen from the side"; 6 seeds): 0.87-0.95x error^2 x CPU on the side- and front-lit r = 10, double HG
// and r = 50 spheres, the box and both Disney clouds, means unchanged; at 512 x 512 2^13 and 2^14 were no
// better than 2^15 (the set-up is a smaller share there), which the sqrt(pixels) growth reaches.
constexpr double kThinCollisions = 1.2;
constexpr int kAutoSideBeamPhotons = 1 << 13;
std::vector<int> auto_beam_photons(const SceneContext& ctx, double cut_angle,
                                   std::optional<double> collisions) {
  const double scale = std::min(8.0, pixel_scale(ctx.camera));
  const bool thin = collisions && *collisions < kThinCollisions;
  // Without a peak (f = 0 in every medium) a scatter is always a wide one: the peak-only beam is the
  // unscattered light, which the straight beam has exactly; a beam grid would only add its noise.
  if (!(cut_angle > 0.0)) return std::vector<int>(ctx.lights.size(), 0);
  std::vector<int> n;
  for (const Light& light : ctx.lights)
    n.push_back(thin || camera_in_forward_peak(ctx, light, cut_angle)
                    ? int(std::round(kAutoBeamPhotons * scale))
                    : int(std::round(std::min(double(kAutoBeamPhotons), kAutoSideBeamPhotons * scale))));
  return n;
}

// "auto" edge samples: 16, and where the camera looks into a directional or point light's forward peak
// (camera_in_forward_peak) 64 up to 128 x 128 pixels, 64 / sqrt(pixels / 128^2) above (16 from 512 x 512 on).
// Looking into the peak, the outline of a dense medium is its brightest part (the silver lining); at small
// sizes a pixel holds much of that thin rim, and its outline pixels are most of the backlit spheres' error once
// the photon grids are denoised (at 512 x 512 far less). Elsewhere the outline is no brighter than the inside
// and more samples there buy nothing (docs/benchmarks.md, "Samples at the outlines"). The full image's
// camera, as auto_beam_photons.
int auto_edge_samples(const SceneContext& ctx, double cut_angle) {
  if (camera_in_any_forward_peak(ctx, cut_angle))
    return int(std::clamp(std::round(64.0 / pixel_scale(ctx.camera)), 16.0, 64.0));
  return 16;
}

// The scatter grid's settings from mfs's (photons resolved; adaptive: they were "auto").
ScatterGridSettings scatter_grid_settings(const MfsSettings& s, bool adaptive, uint64_t seed,
                                          const MajorantGrid* tracking) {
  ScatterGridSettings grid;
  grid.photons = *s.photons;
  grid.adaptive_photons = adaptive ? grid.photons : 0;  // the image size's count, times the pilot's factor
  grid.pilot = !s.beam_photons;                         // "auto" beam photons read the pilot's collisions
  grid.resolution = *s.scatter_grid_resolution;
  grid.max_wide_scatters = s.large_angle_scatters.value_or(0);
  grid.exact_transport = s.photon_transport == PhotonTransport::exact;
  grid.channel_passes = s.channel_passes;
  grid.bands = *s.scatter_grid_bands;
  grid.live_nodes_only = !s.filtered_lookups;  // the pre-filtered levels read every node
  grid.prefiltered = s.filtered_lookups;       // only filtered lookups read them
  grid.splat = s.photon_splat;
  grid.seed = seed;
  grid.majorants = tracking;
  grid.denoise = s.grid_denoise;
  grid.lobe_tail = s.grid_lobe_tail;
  return grid;
}

}  // namespace nimbus
