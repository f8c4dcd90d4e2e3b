#include "integrators/single.h"

#include "core/json_reader.h"
#include "integrators/area_light_view.h"
#include "integrators/camera_layers.h"
#include "integrators/env_light.h"
#include "integrators/surface_light.h"
#include "integrators/tracking.h"
#include "media/phase.h"
#include "scene/lights.h"

namespace nimbus {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
const std::vector<std::string> kTransmittanceNames = {"ratio", "shadow_map"};
}  // namespace

SingleSettings single_settings_from_json(const nlohmann::json& options, const std::string& where) {
  SingleSettings s;
  JsonObject o(options, where, "/integrator");
  s.tau_step = o.number("tau_step", 1e-4, 100.0, s.tau_step);
  s.light_samples = int(o.integer("light_samples", 1, 1024, s.light_samples));
  s.transmittance = Transmittance(o.choice("transmittance", kTransmittanceNames, int(s.transmittance)));
  s.shadow_map_resolution = int(o.integer("shadow_map_resolution", 8, 1024, s.shadow_map_resolution));
  o.finish();
  return s;
}

nlohmann::json to_json(const SingleSettings& s) {
  return {{"tau_step", s.tau_step},
          {"light_samples", s.light_samples},
          {"transmittance", kTransmittanceNames[int(s.transmittance)]},
          {"shadow_map_resolution", s.shadow_map_resolution}};
}

SingleScatter::SingleScatter(const SceneContext& context, SingleSettings settings)
    : ctx_(context), s_(settings) {
  if (s_.transmittance == Transmittance::shadow_map) {
    for (const Light& l : ctx_.lights)  // (area lights: a token map, they march to a sampled point)
      shadow_maps_.emplace_back(ctx_.media, ctx_.majorants, l,
                                is_area_light(l) ? 8 : s_.shadow_map_resolution, 0.05);
  }
}

Rgb SingleScatter::light_transmittance(size_t l, const Vec3& p, const LightSample& ls, Rng& rng) const {
  if (!shadow_maps_.empty() && is_area_light(ctx_.lights[l]))  // the sampled point, marched
    return shadow_transmittance(ctx_, p, ls.wi, ls.distance, rng, kSurfaceShadowStep);
  if (!shadow_maps_.empty())
    return ctx_.surfaces.occluded(p, ls.wi, ls.distance) ? Rgb(0.0) : shadow_maps_[l].lookup(p);
  return shadow_transmittance(ctx_, p, ls.wi, ls.distance, rng);
}

Rgb SingleScatter::Li(const Ray& ray, Rng& rng, CameraSample* sample) const {
  const Rgb L = trace(ray, rng, sample, 1);
  if (!has_visible_area_lights(ctx_)) return L;
  const Rgb Le = visible_area_lights(ctx_, ray, rng, shadow_maps_.empty() ? 0.0 : kSurfaceShadowStep);
  if (sample) sample->direct += Le;  // light straight from a light
  return L + Le;
}

Rgb SingleScatter::trace(const Ray& ray, Rng& rng, CameraSample* sample, int bounces) const {
  const Vec3 &o = ray.o, &d = ray.d;
  SurfaceHit hit;
  const bool on_surface = ctx_.surfaces.intersect(o, d, std::numeric_limits<double>::infinity(), &hit);
  Rgb L(0.0), T(1.0);
  const double jitter = rng.uniform();
  MediumPoint mp;
  MarchRecorder layers(sample);  // depth, albedo and deep segments when the film asks
  march(ctx_.majorants, o, d, hit.t, s_.tau_step, jitter, [&](const Vec3& p, double t, double dt) {
    ctx_.media.eval(p, &mp);
    const Rgb step_T = exp_channels(-mp.sigma_t() * dt);
    Rgb L_step = ctx_.media.emits() ? emission_over_step(mp.emission, T, T * step_T, dt) : Rgb(0.0);
    if (max_component(mp.sigma_s) > 0.0) {
      // Camera-side transmittance to the sample point, then single scattering towards the lights.
      const Rgb T_here = T * exp_channels(-mp.sigma_t() * (jitter * dt));
      Rgb in_scatter(0.0);
      for (int i = 0; i < mp.count; ++i) {
        if (max_component(mp.sigma_s_i[i]) <= 0.0) continue;
        const Phase& phase = ctx_.media.phase(i);
        Rgb Li(0.0);
        for (int s = 0; s < s_.light_samples; ++s) {
          for (size_t l = 0; l < ctx_.lights.size(); ++l) {
            LightSample ls;
            const double u1 = rng.uniform(), u2 = rng.uniform();
            if (!sample_light(ctx_.lights[l], ctx_.light_constants[l], p, u1, u2, &ls)) continue;
            const double f = phase_eval(phase, dot(d, ls.wi));
            if (f <= 0.0) continue;
            Li += ls.weight * f * light_transmittance(l, p, ls, rng);
          }
          if (ctx_.constant_environment()) {
            const double u1 = rng.uniform(), u2 = rng.uniform();
            const Vec3 wi = phase_sample(phase, d, u1, u2);
            Li += ctx_.environment * shadow_transmittance(ctx_, p, wi, kInf, rng);
          }
          if (ctx_.env_map)  // map- and phase-sampled by MIS (integrators/env_light.h)
            Li += medium_env_map_light(*ctx_.env_map, phase, d, rng, [&](const Vec3& wi) {
              return shadow_transmittance(ctx_, p, wi, kInf, rng);
            });
        }
        in_scatter += mp.sigma_s_i[i] * Li / double(s_.light_samples);
      }
      L_step += T_here * in_scatter * dt;
    }
    L += L_step;
    layers.step(t - jitter * dt, dt, T, T * step_T, mp, L_step);
    T *= step_T;
    return max_component(T) > 1e-6;
  });
  // The surface the ray ends on (lit directly, and by the light gathered along one more traced ray) or
  // the environment. All of single's own light is direct; a surface's gathered light is not.
  const GatherFn gather = [&](const Ray& r) { return trace(r, rng, nullptr, bounces - 1); };
  Rgb surface_direct;
  const Rgb L_end =
      ray_end_radiance(ctx_, on_surface ? &hit : nullptr, d, T, rng, sample, bounces > 0 ? &gather : nullptr,
                       &surface_direct, shadow_maps_.empty() ? 0.0 : kSurfaceShadowStep);
  layers.finish(ctx_, d, on_surface ? Rgb(0.0) : T, L + surface_direct);
  return L + L_end;
}

}  // namespace nimbus
