#include "integrators/pathtrace.h"

#include "core/json_reader.h"
#include "integrators/area_light_view.h"
#include "integrators/camera_layers.h"
#include "integrators/env_light.h"
#include "integrators/path_clock.h"
#include "integrators/surface_light.h"
#include "integrators/tracking.h"
#include "scene/lights.h"

namespace nimbus {

namespace {

// A cosine-distributed direction about n; the second number drawn first (the order GCC gave the
// arguments of cosine_direction(n, rng.uniform(), rng.uniform()) before: fixed now for every compiler).
Vec3 diffuse_bounce(const Vec3& n, Rng& rng) {
  const double v2 = rng.uniform(), v1 = rng.uniform();
  return cosine_direction(n, v1, v2);
}

// The depth march's step in optical depth against the majorant (deterministic: no random numbers).
constexpr double kDepthTauStep = 0.02;

// What the camera ray's first flight tells the layers (with a CameraSample): whether it escaped and with
// which weight (an unbiased estimate of the transmittance, from the same random numbers as the beauty),
// where it ended, where its null collisions lay (the transmittance an escaping weight lost), and the NEE
// at its first scattering vertex.
struct FirstFlight {
  const Ray& ray;
  bool active = false, escaped = false, on_surface = false;
  int hit_surface = -1;
  Rgb weight{0.0}, direct{0.0};
  double t_end = 0.0, t_null0 = std::numeric_limits<double>::infinity(), t_null1 = -1.0;

  bool null_collision(int events, const Vec3& p) {  // returns true: tracking goes on
    if (active && events == 0) {
      const double t = dot(p - ray.o, ray.d);
      t_null0 = std::min(t_null0, t);
      t_null1 = std::max(t_null1, t);
    }
    return true;
  }
  void end(bool did_escape, const Rgb& beta, const Vec3& p) {
    escaped = did_escape;
    weight = beta;
    if (!did_escape) t_end = dot(p - ray.o, ray.d);
  }
  void end_on_surface(const SurfaceHit& hit, const Rgb& beta) {
    on_surface = true;
    hit_surface = hit.surface;
    weight = beta;
    t_end = hit.t;
  }
};

// The layers of one camera sample: escape transmittance 1 x weight or 0, direct = background + the first
// NEE (or the first surface's light), depth and albedo by a deterministic march up to the first surface,
// and one deep segment (the whole radiance at the first collision, alpha 1; or an escape's lost alpha
// over its null collisions). A surface's own layers (record_surface_hit) were written when it was met.
void fill_camera_sample(const SceneContext& ctx, const FirstFlight& f, const Rgb& L, CameraSample* s) {
  s->escape_transmittance = f.escaped ? f.weight : Rgb(0.0);
  s->background = f.escaped && ctx.has_environment ? f.weight * ctx.environment_radiance(f.ray.d) : Rgb(0.0);
  s->direct = s->background + f.direct;
  if (s->depth_wanted) march_depth(ctx.media, ctx.majorants, f.ray.o, f.ray.d, kDepthTauStep, s, s->depth);
  if (!s->deep) return;
  // A holdout cuts out what lies behind it, like the background: only the media in front of it remain.
  const bool holdout =
      f.on_surface && !std::holds_alternative<DiffuseMaterial>(ctx.surfaces.material(f.hit_surface));
  if (!f.escaped && !holdout) {
    s->deep->push_back({f.t_end, f.t_end, L - s->background, 1.0});
  } else if (f.t_null1 >= f.t_null0 && average(f.weight) != 1.0) {
    s->deep->push_back({f.t_null0, f.t_null1, L - s->background, 1.0 - average(f.weight)});
  }
}

}  // namespace

PathTraceSettings pathtrace_settings_from_json(const nlohmann::json& options, const std::string& where) {
  PathTraceSettings s;
  JsonObject o(options, where, "/integrator");
  if (const auto k = o.optional_integer("max_wide_scatters", 0, 1 << 20)) s.max_wide_scatters = int(*k);
  if (double f = 0.0; o.keyword_or_number("peak_fraction", "auto", 0.0, 0.99, &f)) s.peak_fraction = f;
  o.finish();
  return s;
}

nlohmann::json to_json(const PathTraceSettings& s) {
  nlohmann::json j = nlohmann::json::object();
  if (s.max_wide_scatters) j["max_wide_scatters"] = *s.max_wide_scatters;
  if (s.peak_fraction) {
    j["peak_fraction"] = *s.peak_fraction;
  } else {
    j["peak_fraction"] = "auto";
  }
  return j;
}

PathTracer::PathTracer(const SceneContext& context, int max_events, PathTraceSettings settings)
    : ctx_(context), max_events_(max_events), s_(settings), clock_reference_(context) {
  if (!s_.max_wide_scatters) return;
  for (int i = 0; i < ctx_.media.count(); ++i) {
    const Phase& phase = ctx_.media.phase(i);
    const double f = s_.peak_fraction ? *s_.peak_fraction : std::min(0.99, auto_peak_fraction(phase));
    splits_.push_back(std::make_unique<PhaseSplit>(phase, f));
  }
}

double PathTracer::split_weight(int medium, double mu, int wide) const {
  if (splits_.empty()) return 1.0;
  const double share = splits_[medium]->wide_share(mu);
  const int K = *s_.max_wide_scatters;
  return (wide + 1 <= K ? share : 0.0) + (wide <= K ? 1.0 - share : 0.0);
}

Rgb PathTracer::direct_light(const Vec3& p, const Vec3& d, int medium, int wide_scatters, Rng& rng,
                             const Rgb& beta, const PathClock& clock) const {
  const size_t timed_from = clock.mark();
  const Phase& phase = ctx_.media.phase(medium);
  Rgb L(0.0);
  // Lights with a sampled direction: weight = radiance / pdf.
  for (const Light& light : ctx_.lights) {
    LightSample ls;
    const double u1 = rng.uniform(), u2 = rng.uniform();
    if (!sample_light(light, p, u1, u2, &ls)) continue;
    const double f = phase_eval(phase, dot(d, ls.wi)) * split_weight(medium, dot(d, ls.wi), wide_scatters);
    if (f <= 0.0) continue;
    const Rgb c = ls.weight * shadow_transmittance(ctx_, p, ls.wi, ls.distance, rng) * f;
    L += c;
    clock.record(clock.connection(p, ls), c);
  }
  // The constant environment through a phase-sampled direction: f / pdf = 1.
  constexpr double kInf = std::numeric_limits<double>::infinity();
  if (ctx_.constant_environment()) {
    const double u1 = rng.uniform(), u2 = rng.uniform();
    const Vec3 wi = phase_sample(phase, d, u1, u2);
    const Rgb T = shadow_transmittance(ctx_, p, wi, kInf, rng);
    const Rgb c = ctx_.environment * T * split_weight(medium, dot(d, wi), wide_scatters);
    L += c;
    clock.record(clock.distant.distance(p, wi), c);
  }
  // The environment image: a map-sampled and a phase-sampled direction by MIS (integrators/env_light.h).
  if (ctx_.env_map) {
    const double u1 = rng.uniform(), u2 = rng.uniform(), v1 = rng.uniform(), v2 = rng.uniform();
    L += env_map_mis(
        *ctx_.env_map, u1, u2, phase_sample(phase, d, v1, v2),
        [&](const Vec3& wi) {
          return Rgb(phase_eval(phase, dot(d, wi)) * split_weight(medium, dot(d, wi), wide_scatters));
        },
        [&](const Vec3& wi) { return phase_eval(phase, dot(d, wi)); },
        [&](const Vec3& wi) { return shadow_transmittance(ctx_, p, wi, kInf, rng); });
  }
  clock.settle(timed_from, beta);
  return beta * L;
}

bool PathTracer::collide(const MediumPoint& mp, double maj, Rgb& beta, Rng& rng, int* scatter_medium) const {
  const Rgb sigma_n = Rgb(maj) - mp.sigma_t();
  // Event probabilities from throughput-weighted channel sums (history-aware spectral tracking, which
  // keeps the per-channel weights bounded); absorption is carried as weight, not sampled.
  const double p_null = std::max(0.0, dot(beta, sigma_n));
  double p_scatter = 0.0;
  for (int i = 0; i < mp.count; ++i) p_scatter += dot(beta, mp.sigma_s_i[i]);
  const double total = p_null + p_scatter;
  if (total <= 0.0) {  // pure absorber at the majorant: the path ends here
    beta = Rgb(0.0);
    return true;
  }
  double u = rng.uniform() * total;
  if (u < p_null) {
    beta *= sigma_n * (total / (maj * p_null));
    return false;
  }
  u -= p_null;
  for (int i = 0; i < mp.count; ++i) {
    const double pi = dot(beta, mp.sigma_s_i[i]);
    if (pi <= 0.0) continue;
    if (u < pi || i == mp.count - 1) {
      beta *= mp.sigma_s_i[i] * (total / (maj * pi));
      *scatter_medium = i;
      return true;
    }
    u -= pi;
  }
  return true;
}

// Russian roulette on the largest channel m of the throughput, from the fourth event on, once m has
// fallen below 0.1 (as Tungsten): the path survives with probability m, its throughput rescaled to 1.
// (Rouletting every event with probability min(1, m) killed 1 - albedo of the paths at each scatter,
// an analogue absorption that cost 8-16 % more variance per sample on the suite's spheres for 3-12 %
// less time: docs/benchmarks.md.)
bool survives_roulette(int events, Rgb& beta, Rng& rng) {
  constexpr double kRouletteBelow = 0.1;
  const double m = max_component(beta);
  if (events < 3 || m >= kRouletteBelow) return true;
  if (rng.uniform() >= m) return false;
  beta /= m;
  return true;
}

Rgb PathTracer::Li(const Ray& ray, Rng& rng, CameraSample* sample) const {
  Rgb L(0.0), beta(1.0);
  Vec3 o = ray.o, d = ray.d;
  int wide = 0;  // wide scatters so far (with a wide-scatter limit)
  MediumPoint mp;
  FirstFlight first{ray, sample != nullptr};
  PathClock clock{sample ? sample->timed : nullptr, clock_reference_};
  for (int events = 0;; ++events) {
    // The free flight ends at the first surface, if any.
    SurfaceHit hit;
    const bool to_surface = ctx_.surfaces.intersect(o, d, std::numeric_limits<double>::infinity(), &hit);
    // Delta tracking to the next real scattering event (analytic media: against their exact extinction).
    int scatter_medium = -1;
    Vec3 scatter_p;
    const bool escaped = track(ctx_, o, d, hit.t, rng, [&](const Vec3& p, double maj) {
      ctx_.media.eval(p, &mp);
      // Emission at every tentative collision, j / majorant: an unbiased estimate of int T j dt.
      if (ctx_.media.emits()) clock.add(L, beta * mp.emission / maj, clock.from(o, p));
      if (!collide(mp, maj, beta, rng, &scatter_medium)) return first.null_collision(events, p);
      scatter_p = p;
      return false;
    });
    if (escaped && to_surface) {
      if (events == 0 && sample) {
        first.end_on_surface(hit, beta);
        record_surface_hit(ctx_, hit, beta, sample);
      }
      const Rgb L_before = L;
      clock.walk(o, hit.p);
      const bool goes_on = reflect(hit, L, beta, wide, rng, clock);
      if (events == 0) first.direct = L - L_before;
      if (!goes_on || (max_events_ > 0 && events + 1 >= max_events_)) break;
      d = diffuse_bounce(hit.ns, rng);
      if (dot(d, hit.ng) <= 0.0) break;  // below the geometric surface (shading normals): absorbed
      o = SceneSurfaces::offset(hit, d);
    } else if (escaped) {
      if (events == 0) first.end(true, beta, scatter_p);
      // Only camera rays see the environment directly; later escapes were counted by NEE.
      if (events == 0 && ctx_.has_environment) clock.background(L, beta * ctx_.environment_radiance(d), o, d);
      break;
    } else {
      if (events == 0) first.end(false, beta, scatter_p);
      if (scatter_medium < 0 || max_component(beta) <= 0.0) break;
      // Next-event estimation at the scattering vertex.
      clock.walk(o, scatter_p);
      const Rgb L_direct = direct_light(scatter_p, d, scatter_medium, wide, rng, beta, clock);
      L += L_direct;
      if (events == 0) first.direct = L_direct;
      if (max_events_ > 0 && events + 1 >= max_events_) break;
      if (!scatter(scatter_medium, d, wide, rng)) break;
      o = scatter_p;
    }

    if (!survives_roulette(events, beta, rng)) break;
  }
  const Rgb Le = visible_area_lights(ctx_, ray, rng, 0.0, clock.out);  // lights the camera sees
  L += Le, first.direct += Le;
  if (sample) fill_camera_sample(ctx_, first, L, sample);
  return L;
}

bool PathTracer::scatter(int medium, Vec3& d, int& wide, Rng& rng) const {
  // Continue in a phase-sampled direction (weight f / pdf = 1).
  const double u1 = rng.uniform(), u2 = rng.uniform();
  const Vec3 d_new = phase_sample(ctx_.media.phase(medium), d, u1, u2);
  if (!splits_.empty()) {
    // Classify the scatter (probability = its wide share); paths over the limit end here.
    const double share = splits_[medium]->wide_share(dot(d, d_new));
    if (rng.uniform() < share && ++wide > *s_.max_wide_scatters) return false;
  }
  d = d_new;
  return true;
}

bool PathTracer::reflect(const SurfaceHit& hit, Rgb& L, Rgb& beta, int& wide, Rng& rng,
                         const PathClock& clock) const {
  const Material& material = ctx_.surfaces.material(hit.surface);
  const auto* diffuse = std::get_if<DiffuseMaterial>(&material);
  if (!diffuse) return false;  // a holdout: black, and the path ends
  // A diffuse reflection is a wide scatter (with a wide-scatter limit).
  if (!splits_.empty() && ++wide > *s_.max_wide_scatters) return false;
  // Direct light and the environment (a transient render: each part with its light connection's length).
  const PathClock* timed = clock.on() ? &clock : nullptr;
  L += beta *
       clock.settled(beta, [&] { return surface_radiance(ctx_, hit, rng, nullptr, nullptr, 0.0, timed); });
  beta *= diffuse->albedo;
  return max_component(beta) > 0.0;
}

}  // namespace nimbus
