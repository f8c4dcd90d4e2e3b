#include "integrators/mfs.h"

#include <fmt/format.h>

#include <algorithm>
#include <limits>
#include <optional>

#include "core/json_reader.h"
#include "integrators/area_light_view.h"
#include "integrators/camera_layers.h"
#include "integrators/env_light.h"
#include "integrators/mfs_estimators.h"
#include "integrators/mfs_settings.h"
#include "integrators/surface_light.h"
#include "integrators/tracking.h"
#include "media/density_grid.h"
#include "nimbus/error.h"

namespace nimbus {

namespace {

// eq. D19's drift rate per unit peak depth, 1 - chi_1 of the peak (0 without one). Only with camera_fluence:
// otherwise the march keeps no drift depth.
double peak_drift(const PhaseSplit& split) {
  const std::vector<double>& chi = split.peak_moments();
  return split.f() > 0.0 && chi.size() > 1 ? std::max(0.0, 1.0 - chi[1]) : 0.0;
}

double pieces_max_step(const SceneContext& ctx, const ScatterGrid* grid, const BeamGrid* beam) {
  // The pieces' march (constant-density shapes) steps at most kMaxStepSpacings node spacings of the photon
  // grids: the light they hold varies on that scale (the majorant grid's cells, of about the size of one,
  // bound the steps elsewhere). Without grids, kMaxStepSpacings / 32 of the media's extent, as those cells.
  // (The spacing along the grids' longest axis: a flat box's thin axis has a spacing of its own thickness.)
  // One spacing while the steps shared their offset; with StepOffsets (tracking.h) two cost 0.74-0.84x the
  // CPU at 512 x 512 for the same error within 0.04 points (docs/benchmarks.md, "The march's offsets").
  constexpr double kMaxStepSpacings = 2.0;
  const auto spacing = [](const NodeGrid& g) { return std::max({g.spacing.x, g.spacing.y, g.spacing.z}); };
  const Vec3 extent = ctx.media.bounds().hi - ctx.media.bounds().lo;
  double step = std::max({extent.x, extent.y, extent.z}) / 32.0;
  if (grid) step = std::min(step, spacing(grid->node_grid()));
  if (beam) step = std::min(step, spacing(beam->node_grid()));
  step *= kMaxStepSpacings;
  return step > 0.0 ? step : std::numeric_limits<double>::infinity();  // no media: no pieces
}

// The moments chi_l a grid lookup takes for a medium with this split, l < the result: with the lobe tail
// (ScatterGrid::moments_read) only where the wide part's chi_3..5 reach 0.04 in size, HG from g ~ 0.77 on (0.068
// for HG 0.85, 0.033 for HG 0.7). Below, the tail changed nothing measurable (the r = 1 sphere's HG 0.7:
// 0.05 points) and cost 6 % of the CPU at 512 x 512 (its three more exps and its lobe per lookup).
int tail_moments(const ScatterGrid& grid, const PhaseSplit& split) {
  const std::vector<double>& chi = split.wide_moments();
  double most = 0.0;
  for (size_t l = 3; l < size_t(kShMaxBands) && l < chi.size(); ++l) most = std::max(most, std::abs(chi[l]));
  return most >= 0.04 ? grid.moments_read() : grid.bands();
}

}  // namespace

MfsIntegrator::MfsIntegrator(const SceneContext& context, MfsSettings settings, uint64_t seed)
    : ctx_(context), s_(settings) {
  for (int i = 0; i < ctx_.media.count(); ++i) {
    const Phase& phase = ctx_.media.phase(i);
    const double f = s_.peak_fraction ? *s_.peak_fraction : std::min(0.99, auto_peak_fraction(phase));
    splits_.push_back(std::make_unique<PhaseSplit>(phase, f, s_.propagator == Propagator::gaussian));
    f_.push_back(splits_.back()->f());
    theta2_.push_back(splits_.back()->theta2());
    if (s_.camera_fluence && !s_.path_lengthening) drift_.push_back(peak_drift(*splits_.back()));  // eq. D19
  }
  double cut_angle = 0.0;  // the widest peak's, for "auto" beam photons
  for (const auto& sp : splits_)
    if (sp->f() > 0.0) cut_angle = std::max(cut_angle, sp->cut_angle());
  const bool auto_beam = !s_.beam_photons;
  beam_counts_ = s_.beam_photons ? std::vector<int>(ctx_.lights.size(), *s_.beam_photons)
                                 : auto_beam_photons(ctx_, cut_angle);
  if (!s_.edge_samples) s_.edge_samples = auto_edge_samples(ctx_, cut_angle);
  // The light's chord in closed form where there is one (the maps' interpolation errs at sharp rims).
  if (!s_.exact_light_transmittance)
    s_.exact_light_transmittance = ctx_.analytic.active() && ctx_.media.count() == 1;
  build_maps();
  if (!s_.scatter_grid_resolution) s_.scatter_grid_resolution = auto_scatter_grid_resolution(ctx_);
  if (!s_.photons) s_.photons = auto_photons(ctx_, cut_angle);
  const std::optional<MajorantGrid> photon_majorants = photon_majorant_grid(ctx_, s_, beam_counts_);
  const MajorantGrid* tracking = photon_majorants ? &*photon_majorants : nullptr;
  std::vector<const PhaseSplit*> splits;  // for the photon grids
  for (const auto& sp : splits_) splits.push_back(sp.get());
  if (!s_.scatter_grid_bands) s_.scatter_grid_bands = auto_scatter_grid_bands(splits);
  // Wide scatters 2 .. K from the scatter grid (for K = 1 only the environment's light).
  if (s_.large_angle_scatters != 0 &&
      (s_.large_angle_scatters != 1 || ctx_.has_environment || ctx_.media.emits())) {
    grid_ = std::make_unique<ScatterGrid>(ctx_, splits, f_,
                                          scatter_grid_settings(s_, !settings.photons, seed, tracking));
    s_.photons = grid_->photons();
    for (const PhaseSplit* sp : splits) grid_moments_.push_back(tail_moments(*grid_, *sp));
    // Thin media take more beam photons (auto_beam_photons); the tracking grid above counted the fewer.
    if (auto_beam && grid_->collisions_per_photon())
      beam_counts_ = auto_beam_photons(ctx_, cut_angle, grid_->collisions_per_photon());
  }
  if (!beam_counts_.empty() &&
      std::all_of(beam_counts_.begin(), beam_counts_.end(), [&](int n) { return n == beam_counts_[0]; }))
    s_.beam_photons = beam_counts_[0];  // the header's settings: one count for every light, or "auto"
  if (beam_on()) build_beam(splits, tracking, seed);
  max_step_ = pieces_max_step(ctx_, grid_.get(), beam_.get());
  if (grid_ && beam_) {
    const NodeGrid &a = grid_->node_grid(), &b = beam_->node_grid();
    shared_stencil_ = a.bounds.lo == b.bounds.lo && a.bounds.hi == b.bounds.hi && a.nodes == b.nodes &&
                      a.spacing == b.spacing;
  }
}

void MfsIntegrator::build_maps() {
  // Shadow-map nodes march towards the light at this optical-depth step (midpoint rule). 0.05 and 0.5
  // give the same validation errors (the map's trilinear interpolation dominates); 0.25 halves the
  // Disney cloud's precomputation against 0.05.
  constexpr double map_step = 0.25;
  const bool beam = beam_on();
  for (const Light& l : ctx_.lights) {
    const int res = is_area_light(l) ? 8 : s_.shadow_map_resolution;  // area lights: a token map (light_beam)
    if (*s_.exact_light_transmittance) {
      // light_beam reads the chord: only the beam grid's photons read the maps (the reduced one, and
      // for the traced spread the full one too), and on one constant-density shape they read the chord
      // too (empty maps: BeamGrid).
      const bool chord = ctx_.analytic.active() && ctx_.media.count() == 1;
      if (s_.forward_light_path() && beam && !chord && s_.beam_spread == BeamSpread::traced) {
        TransmittanceGrid::build_pair(ctx_.media, ctx_.majorants, l, res, map_step, f_,
                                      &full_maps_.emplace_back(), &reduced_maps_.emplace_back());
      } else {
        full_maps_.emplace_back();
        if (s_.forward_light_path())
          reduced_maps_.push_back(beam && !chord
                                      ? TransmittanceGrid(ctx_.media, ctx_.majorants, l, res, map_step, f_)
                                      : TransmittanceGrid());
      }
    } else if (s_.forward_light_path()) {
      TransmittanceGrid::build_pair(ctx_.media, ctx_.majorants, l, res, map_step, f_,
                                    &full_maps_.emplace_back(), &reduced_maps_.emplace_back());
    } else {
      full_maps_.emplace_back(ctx_.media, ctx_.majorants, l, res, map_step);
    }
  }
}

size_t MfsIntegrator::memory_bytes() const {
  size_t bytes = (grid_ ? grid_->memory_bytes() : 0) + (beam_ ? beam_->memory_bytes() : 0);
  for (const auto& m : full_maps_) bytes += m.memory_bytes();
  for (const auto& m : reduced_maps_) bytes += m.memory_bytes();
  return bytes;
}

// The radiance along the camera ray as the sum of the estimators in mfs_estimators.h over a march fixed
// in optical depth (docs/derivations.md: eq. D7 for the first wide scatter and the forward peak, D11 for
// forward_side "light", D12 for the higher orders, D13 for the growing steps).
//
// A surface the ray ends on gathers one ray, and the surface that ray meets one more (kSurfaceBounces):
// light that goes between surfaces twice (a cube's faces lit by the ground it lights, the ground lit by
// the fog's light) was missing with one. On the Cycles-comparison scene j_mesh (a cube and a ground in
// thin fog) the mean went from -1.25 % to -0.8 % and the binned error from 2.9 % to 2.1 % at +2 % of the
// CPU; a third bounce bought -0.7 % and 2.0 % at +7 % (docs/validation/surfaces.md). Scenes whose
// gathered rays meet no second surface (a ground alone) are unchanged.
constexpr int kSurfaceBounces = 2;
Rgb MfsIntegrator::Li(const Ray& ray, Rng& rng, CameraSample* sample) const {
  const Rgb L = trace(ray, rng, sample, kSurfaceBounces);
  if (!has_visible_area_lights(ctx_)) return L;
  const Rgb Le = visible_area_lights(ctx_, ray, rng, kSurfaceShadowStep);
  if (sample) sample->direct += Le;  // light straight from a light
  return L + Le;
}

Rgb MfsIntegrator::trace(const Ray& ray, Rng& rng, CameraSample* sample, int bounces) const {
  const Vec3 &o = ray.o, &d = ray.d;
  SurfaceHit hit;
  const bool on_surface = ctx_.surfaces.intersect(o, d, std::numeric_limits<double>::infinity(), &hit);
  Rgb L(0.0);
  CameraPath cam;  // from the camera to the current step: T_full, T_red, tau_p, theta_p, tau_red, m0..m2
  const double jitter = rng.uniform();  // the march's first offset (StepOffsets: the others follow)
  std::optional<FootprintProbe> probe = footprint_probe(d, rng);  // camera_tilt's offsets (eq. D16)
  MediumPoint mp;
  MarchRecorder layers(sample);  // direct: the lights' light that took at most one wide scatter
  const ShBasis y_out(-d, grid_ ? grid_->bands() : 1);  // the scatter grid's basis towards the camera
  Rgb direct(0.0);
  // Steps of tau_step (1 + step_growth tau_red); fixed steps of at most kEmissionStep where a medium may
  // emit (eq. D13: growing steps would sample the emission's variation, which no blur smooths, too coarsely).
  const auto scale = [&](double t0, double t1) {
    return ctx_.majorants.may_emit_at(o + d * (0.5 * (t0 + t1)))
               ? std::min(1.0, kEmissionStep / s_.tau_step)
               : 1.0 + s_.step_growth * max_component(cam.tau_red);
  };
  const auto step = [&](const Vec3& p, double t, double dt, double u) {
    ++mfs_march_steps;
    // Split the extinction at p into peak and reduced parts (eq. D2).
    ctx_.media.eval(p, &mp);
    const MfsExtinction k = mfs_extinction(mp, f_, theta2_, drift_);
    Rgb L_step(0.0);
    // Add what each medium scatters towards the camera at the sample point y = p.
    if (max_component(mp.sigma_s) > 0.0) {
      const CameraPoint y = cam.at(k, u, dt, s_.light_side(), s_.path_lengthening, s_.camera_fluence);
      const Sources src = step_sources(mp, p, d, y_out, t, y, cam, rng, probe ? &*probe : nullptr);
      L_step = (y.T_cam * src.in_scatter + y.T_full * src.peak_scatter) * dt;
      L += L_step;
      direct += (y.T_cam * src.lights_scatter + y.T_full * src.peak_scatter) * dt;
    }
    // Advance the camera-side state over the whole step.
    const Rgb T0 = s_.light_side() ? cam.T_full : cam.T_red;
    cam.advance(k, t, dt, u);
    if (ctx_.media.emits()) {  // emission along the ray, through the same transmittance as the grid's light
      const Rgb E = emission_over_step(mp.emission, T0, s_.light_side() ? cam.T_full : cam.T_red, dt);
      L += E;
      L_step += E;
    }
    layers.step(t - u * dt, dt, T0, s_.light_side() ? cam.T_full : cam.T_red, mp, L_step);
    return max_component(s_.light_side() ? cam.T_full : cam.T_red) > 1e-6;
  };
  // Constant-density shapes: steps over their pieces, by optical depth alone (tracking.h).
  if (ctx_.analytic.active())
    march_growing(ctx_.analytic, o, d, hit.t, s_.tau_step, max_step_, jitter, scale, step);
  else
    march_growing(ctx_.majorants, o, d, hit.t, s_.tau_step, jitter, scale, step);
  // Add the surface the ray ends on (lit directly and by one gathered ray) or the environment behind the
  // medium (its scattered light is in the grid). Camera side: light smooth in angle keeps its
  // peak-scattered part on the ray, so only the reduced extinction removes it.
  const Rgb T_end = s_.light_side() ? cam.T_full : cam.T_red;
  const GatherFn gather = [&](const Ray& r) { return trace(r, rng, nullptr, bounces - 1); };
  Rgb surface_direct;
  const Rgb L_end = ray_end_radiance(ctx_, on_surface ? &hit : nullptr, d, T_end, rng, sample,
                                     bounces > 0 ? &gather : nullptr, &surface_direct, kSurfaceShadowStep);
  layers.finish(ctx_, d, on_surface ? Rgb(0.0) : T_end, direct + surface_direct);
  return L + L_end;
}

MfsIntegrator::Sources MfsIntegrator::step_sources(const MediumPoint& m, const Vec3& p, const Vec3& d,
                                                   const ShBasis& y_out, double t, const CameraPoint& y,
                                                   const CameraPath& cam, Rng& rng,
                                                   FootprintProbe* probe) const {
  Sources src;
  double residual = 1.0, kept = 1.0;
  bool bulk = false;
  if (s_.light_side()) {  // forward_side "light" has no camera-side spread
    add_sources(m, p, d, d, y_out, t, y, cam, rng, true, true, &src);
  } else if (s_.source_blur) {
    add_sources(m, p, d, d, y_out, t, y, cam, rng, false, true, &src);
    add_blurred_sources(p, d, y_out, t, y, cam, rng, &src);
  } else if (Vec3 d_s; probe && tilt(p, d, t, cam, *probe, &d_s, &residual, &bulk, &kept)) {
    if (bulk) {  // eq. D17: the lights' first wide scatter tilted along their beams' gradients
      CameraPoint y_g = y;
      y_g.gradient_tilt = cam.offset_deflection_covariance(t) * y.sigma_red;
      y_g.gradient_spread = cam.lateral_spread(t);
      add_sources(m, p, d, d, y_out, t, y_g, cam, rng, true, true, &src);
    } else {
      CameraPoint y_s = y;  // the scattered light: the tilted direction and the residual spread
      y_s.tau_p = y.tau_p * residual;
      const ShBasis y_out_s(-d_s, grid_ ? grid_->bands() : 1);
      add_sources(m, p, d, d_s, y_out_s, t, y_s, cam, rng, true, true, &src);
    }
  } else {
    add_sources(m, p, d, d, y_out, t, y, cam, rng, true, true, &src);
  }
  if (kept < 1.0) {  // eq. D18: the scattered light of the footprint's half that left by the entry face
    src.in_scatter *= kept;
    src.lights_scatter *= kept;
  }
  return src;
}

std::optional<FootprintProbe> MfsIntegrator::footprint_probe(const Vec3& d, Rng& rng) const {
  if (!s_.camera_tilt || s_.source_blur || s_.light_side() || !s_.forward_light_path()) return std::nullopt;
  const double u1 = rng.uniform(), u2 = rng.uniform();  // in this order (argument order is unspecified)
  return FootprintProbe(d, u1, u2);
}

bool MfsIntegrator::tilt(const Vec3& p, const Vec3& d, double t, const CameraPath& cam, FootprintProbe& probe,
                         Vec3* d_s, double* residual, bool* bulk, double* kept) const {
  const double sigma = cam.lateral_spread(t);
  if (!(sigma > 0.0)) return false;
  const Vec3 u = probe.next(sigma);
  const bool plus = ctx_.media.inside(p + u), minus = ctx_.media.inside(p - u);
  if (s_.entry_loss && !(plus && minus)) {  // eq. D18
    const double r = u.length();
    *kept = 0.5 * ((plus || !before_entry(p + u, d, r) ? 1.0 : 0.0) +
                   (minus || !before_entry(p - u, d, r) ? 1.0 : 0.0));
  }
  if (plus && minus && s_.camera_shift) {  // eq. D17: the bulk
    *bulk = true;
    return true;
  }
  if (plus == minus) return false;
  *d_s = survivor_direction(cam, t, d, plus ? u : -u, residual);
  return true;
}

bool MfsIntegrator::before_entry(const Vec3& q, const Vec3& d, double r) const {
  // Nearest first, ahead then behind: the first medium met decides.
  for (const double k : {0.25, 0.5, 1.0, 2.0, 4.0}) {
    if (ctx_.media.inside(q + d * (k * r))) return true;
    if (ctx_.media.inside(q - d * (k * r))) return false;
  }
  return false;  // no medium along the line near q: it passed beside the media
}

void MfsIntegrator::add_blurred_sources(const Vec3& p, const Vec3& d, const ShBasis& y_out, double t,
                                        const CameraPoint& y, const CameraPath& cam, Rng& rng,
                                        Sources* out) const {
  // T_cam's light left its last scatter in the lateral footprint of depth t (eq. D14): the source there,
  // zero outside the media.
  const double u1 = rng.uniform(), u2 = rng.uniform();  // in this order (argument order is unspecified)
  const Vec3 ps = p + lateral_offset(d, cam.lateral_spread(t), u1, u2);
  MediumPoint m;
  ctx_.media.eval(ps, &m);
  add_sources(m, ps, d, d, y_out, t, y, cam, rng, true, false, out);
}

void MfsIntegrator::add_sources(const MediumPoint& m, const Vec3& p, const Vec3& d, const Vec3& d_s,
                                const ShBasis& y_out, double t, const CameraPoint& y, const CameraPath& cam,
                                Rng& rng, bool scattered, bool peak, Sources* out) const {
  std::optional<TrilinearStencil> st;
  if (shared_stencil_) st = grid_->node_grid().stencil(p);
  for (int i = 0; i < m.count; ++i) {
    if (max_component(m.sigma_s_i[i]) <= 0.0) continue;
    const MediumRadiance Lm = medium_radiance(i, p, d, d_s, y_out, t, y, cam, rng, st ? &*st : nullptr);
    if (scattered) out->in_scatter += m.sigma_s_i[i] * Lm.L;
    if (peak) out->peak_scatter += m.sigma_s_i[i] * Lm.L_peak;
    if (scattered) out->lights_scatter += m.sigma_s_i[i] * Lm.L_lights;
  }
}

MfsIntegrator::MediumRadiance MfsIntegrator::medium_radiance(int i, const Vec3& p, const Vec3& d,
                                                             const Vec3& d_s, const ShBasis& y_out, double t,
                                                             const CameraPoint& y, const CameraPath& cam,
                                                             Rng& rng, const TrilinearStencil* st) const {
  const PhaseSplit& split = *splits_[i];
  const double f = f_[i];
  MediumRadiance out{Rgb(0.0), Rgb(0.0), Rgb(0.0)};
  // peak_ and wide_toward_camera's tallies hold the light sent towards the camera: used on rays from it only.
  const auto camera_ray = [&] {
    const Vec3 v = p - ctx_.camera.origin(), c = cross(v, d);
    return dot(v, d) > 0.0 && dot(c, c) <= 1e-12 * dot(v, v);
  };
  // A light's first wide scatter and forward peak at p, from its sample ls and the beam towards it.
  auto add_light = [&](const LightSample& ls, const LightBeam& beam) {
    const double mu = dot(d, ls.wi);
    if (s_.light_side()) {
      out.L += light_side_scatter(ls.weight, f, split, mu, beam.tau_ps, beam.T_wide);  // eq. D11
      return;
    }
    const PhaseSplit::Angle a = PhaseSplit::angle(mu);  // once for both terms
    const PhaseSplit::Angle a_s =  // the scattered light's: camera_tilt's (D16) or camera_shift's (D17, D17b)
        y.gradient_tilt > 0.0
            ? PhaseSplit::angle(
                  dot(gradient_tilted(d_s, ls.wi, cut_gradient_tilt(y, d_s, ls.wi, beam.T_wide)), ls.wi))
        : !(d_s == d) ? PhaseSplit::angle(dot(d_s, ls.wi))
                      : a;
    const Rgb T_first = beam.wide && camera_ray() ? beam.T_wide * beam.wide_ratio : beam.T_wide;  // eq. D20
    if (s_.large_angle_scatters != 0)  // eq. D7, first term
      out.L += first_wide_scatter(ls.weight, f, split, a_s, y.tau_p, s_.light_blur ? beam.tau_ps : Rgb(0.0),
                                  T_first);
    if (s_.forward_light_path() && beam.toward && camera_ray())  // the traced beam's P_peak to the camera
      out.L_peak += ls.weight * f * beam.peak_toward * beam.T_wide;
    else if (s_.forward_light_path())  // eq. D7, second term: to the camera with T_full
      out.L_peak += forward_peak(ls.weight, f, split, a, beam.tau_ps, beam.T_wide);
    else  // eq. D7b (beer_lambert)
      out.L += forward_peak(ls.weight, f, split, a, y.tau_p, beam.T_light);
  };
  // Sample every light once (u1, u2, in this order).
  for (size_t l = 0; l < ctx_.lights.size(); ++l) {
    LightSample ls;
    const double u1 = rng.uniform(), u2 = rng.uniform();
    if (!sample_light(ctx_.lights[l], ctx_.light_constants[l], p, u1, u2, &ls)) continue;
    if (ctx_.surfaces.occluded(p, ls.wi, ls.distance)) continue;  // a surface shadows y
    add_light(ls, light_beam(l, i, p, ls, st));
  }
  // An environment image is one more light: a direction drawn as its photons leave it (the image by
  // luminance, with any constant part), so that the grid, which carries the image's photons only
  // after their first wide scatter, and this term share its light without overlap.
  if (ctx_.env_map) {
    const double u1 = rng.uniform(), u2 = rng.uniform();
    LightSample ls;
    double pdf = 0.0;
    ls.wi = env_photon_direction(ctx_, u1, u2, &pdf);
    if (pdf > 0.0 && !ctx_.surfaces.occluded(p, ls.wi, ls.distance)) {
      ls.weight = ctx_.environment_radiance(ls.wi) / pdf;
      add_light(ls, environment_beam(i, p, ls.wi));
    }
  }
  // Add the light that already took wide scatters (and the environment's): its last wide scatter is at y.
  out.L_lights = out.L;
  if (grid_) out.L += higher_orders(i, p, y_out, t, y.tau_p, cam, st);
  return out;
}

LightBeam MfsIntegrator::environment_beam(int i, const Vec3& p, const Vec3& wi) const {
  Rgb T_light, T_wide;
  marched_full_and_reduced(ctx_, p, wi, std::numeric_limits<double>::infinity(), kSurfaceShadowStep, f_,
                           &T_light, &T_wide);
  if (!s_.forward_light_path()) T_wide = T_light;
  return peak_only_beam(T_light, T_wide, false, Rgb(1.0), nullptr, splits_[i]->peak_moments(), theta2_[i],
                        s_.forward_light_path() && s_.path_lengthening);
}

void MfsIntegrator::build_beam(const std::vector<const PhaseSplit*>& splits, const MajorantGrid* tracking,
                               uint64_t seed) {
  // peak_toward_camera, wide_toward_camera: P_peak, P_wide towards the camera tallied too (one medium only).
  const Vec3 camera = ctx_.camera.origin();
  const bool one = ctx_.media.count() == 1;
  const BeamCameraTallies tallies{.peak = s_.peak_toward_camera && one, .wide = s_.wide_toward_camera && one};
  beam_ = std::make_unique<BeamGrid>(ctx_, splits, f_, full_maps_, reduced_maps_, beam_counts_,
                                     *s_.scatter_grid_resolution, seed, s_.beam_spread == BeamSpread::traced,
                                     tallies.peak || tallies.wide ? &camera : nullptr, tracking, true,
                                     s_.beam_smoothing, tallies);
}

void MfsIntegrator::exact_light_transmittance(const Vec3& p, const LightSample& ls, Rgb* T_light,
                                              Rgb* T_wide) const {
  // One constant-density sphere or box: the chord to the light in closed form. The shadow maps'
  // interpolation over-estimates T where the light grazes a sharp boundary (the chord grows like sqrt of
  // the distance to the tangent point): a backlit sphere's rim (less since the maps interpolate depth).
  if (chord_full_and_reduced(ctx_, p, ls.wi, ls.distance, f_, T_light, T_wide)) return;
  marched_full_and_reduced(ctx_, p, ls.wi, ls.distance, kSurfaceShadowStep, f_, T_light, T_wide);
}

LightBeam MfsIntegrator::light_beam(size_t l, int i, const Vec3& p, const LightSample& ls,
                                    const TrilinearStencil* st) const {
  Rgb T_light, T_wide;
  if (is_area_light(ctx_.lights[l])) {
    // An area light: to its sampled point instead of a map, by the chord where there is one in closed
    // form (one constant-density sphere or box), else marched.
    if (!chord_full_and_reduced(ctx_, p, ls.wi, ls.distance, f_, &T_light, &T_wide))
      marched_full_and_reduced(ctx_, p, ls.wi, ls.distance, kSurfaceShadowStep, f_, &T_light, &T_wide);
    if (!s_.forward_light_path()) T_wide = T_light;
  } else if (*s_.exact_light_transmittance) {
    exact_light_transmittance(p, ls, &T_light, &T_wide);
    if (!s_.forward_light_path()) T_wide = T_light;
  } else {
    const TrilinearStencil map_st = full_maps_[l].stencil(p);  // the pair's shared layout (build_pair)
    T_light = full_maps_[l].lookup(map_st);
    T_wide = s_.forward_light_path() ? reduced_maps_[l].lookup(map_st) : T_light;
  }
  Rgb R(1.0), mean_cos(1.0), toward(0.0), wide_ratio(1.0);
  Rgb* spread = s_.beam_spread == BeamSpread::traced ? &mean_cos : nullptr;  // else the straight beam's
  const bool traced =
      beam_ && (st ? beam_->lookup(l, p, *st, T_light, T_wide, &R, spread, &toward, &wide_ratio)
                   : beam_->lookup(l, p, T_light, T_wide, &R, spread, &toward, &wide_ratio));
  LightBeam b = peak_only_beam(T_light, T_wide, traced, R, spread, splits_[i]->peak_moments(), theta2_[i],
                               s_.forward_light_path() && s_.path_lengthening);
  if (traced && beam_->has_camera()) {
    b.toward = true;
    b.peak_toward = toward;
  }
  if (traced && beam_->has_wide()) {
    b.wide = true;
    b.wide_ratio = wide_ratio;
  }
  return b;
}

Rgb MfsIntegrator::higher_orders(int i, const Vec3& p, const ShBasis& y_out, double t, const Rgb& tau_p,
                                 const CameraPath& cam, const TrilinearStencil* st) const {
  const PhaseSplit& split = *splits_[i];
  const double f = f_[i];
  const auto scattered = [&](const std::array<Rgb, kShMaxBands>& chi) {
    return st ? grid_->scattered(p, *st, y_out, chi) : grid_->scattered(p, y_out, chi);
  };
  // forward_side "light": the whole phase function at y, exact camera leg (eq. D12 with D1's moments).
  if (s_.light_side()) return scattered(whole_phase_moments(split, f, grid_moments_[size_t(i)]));
  // Camera side: the wide part, its moments blurred by the camera-side peak depth (eqs. D3, D12),
  // optionally read pre-filtered over the camera-side lateral spread (eq. D10).
  const std::array<Rgb, kShMaxBands> chi = blurred_wide_moments(split, tau_p, grid_moments_[size_t(i)]);
  return (1.0 - f) * (s_.filtered_lookups ? grid_->scattered_filtered(p, y_out, chi, cam.lateral_spread(t))
                                          : scattered(chi));
}

}  // namespace nimbus
