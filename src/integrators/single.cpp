#include "integrators/single.h"

#include "integrators/tracking.h"
#include "io/json_reader.h"
#include "render/lights.h"

namespace nimbus {

SingleSettings parse_single_settings(const nlohmann::json& options, const std::string& where, bool strict) {
  SingleSettings s;
  JsonObject o(options, where, "/integrator");
  s.tau_step = o.number("tau_step", 1e-4, 100.0, s.tau_step);
  s.light_samples = int(o.integer("light_samples", 1, 1024, s.light_samples));
  const std::string transmittance = o.string("transmittance", "ratio");
  if (transmittance != "ratio" && transmittance != "shadow_map")
    o.fail("transmittance", "must be \"ratio\" or \"shadow_map\"");
  s.shadow_map = transmittance == "shadow_map";
  s.shadow_map_resolution = int(o.integer("shadow_map_resolution", 8, 1024, s.shadow_map_resolution));
  if (strict) o.finish();
  return s;
}

SingleScatter::SingleScatter(const SceneContext& context, SingleSettings settings)
    : ctx_(context), s_(settings) {
  if (s_.shadow_map) {
    for (const Light& l : ctx_.lights)
      shadow_maps_.emplace_back(ctx_.media, ctx_.majorants, l, s_.shadow_map_resolution, 0.05);
  }
}

Rgb SingleScatter::light_transmittance(size_t l, const Vec3& p, const LightSample& ls, Rng& rng) const {
  if (!shadow_maps_.empty()) return shadow_maps_[l].lookup(p);
  return ratio_tracking_transmittance(ctx_.media, ctx_.majorants, p, ls.wi, ls.distance, rng);
}

Rgb SingleScatter::sample(double px, double py, Rng& rng) const {
  return radiance(ctx_.camera.origin(), ctx_.camera.direction(px, py), rng);
}

Rgb SingleScatter::radiance(const Vec3& o, const Vec3& d, Rng& rng) const {
  Rgb L(0.0), T(1.0);
  const double jitter = rng.uniform();
  MediumPoint mp;
  march(ctx_.majorants, o, d, std::numeric_limits<double>::infinity(), s_.tau_step, jitter,
        [&](const Vec3& p, double, double dt) {
          ctx_.media.eval(p, &mp);
          const Rgb step_T = exp(-mp.sigma_t() * dt);
          if (max_component(mp.sigma_s) > 0.0) {
            // Camera-side transmittance to the sample point, then single scattering towards the lights.
            const Rgb T_here = T * exp(-mp.sigma_t() * (jitter * dt));
            Rgb in_scatter(0.0);
            for (int i = 0; i < mp.count; ++i) {
              if (max_component(mp.sigma_s_i[i]) <= 0.0) continue;
              const Phase& phase = ctx_.media.phase(i);
              Rgb Li(0.0);
              for (int s = 0; s < s_.light_samples; ++s) {
                for (size_t l = 0; l < ctx_.lights.size(); ++l) {
                  LightSample ls;
                  const double u1 = rng.uniform(), u2 = rng.uniform();
                  if (!sample_light(ctx_.lights[l], p, u1, u2, &ls)) continue;
                  const double f = phase_eval(phase, dot(d, ls.wi));
                  if (f <= 0.0) continue;
                  Li += ls.weight * f * light_transmittance(l, p, ls, rng);
                }
                if (ctx_.has_environment) {
                  const double u1 = rng.uniform(), u2 = rng.uniform();
                  const Vec3 wi = phase_sample(phase, d, u1, u2);
                  Li += ctx_.environment *
                        ratio_tracking_transmittance(ctx_.media, ctx_.majorants, p, wi,
                                                     std::numeric_limits<double>::infinity(), rng);
                }
              }
              in_scatter += mp.sigma_s_i[i] * Li / double(s_.light_samples);
            }
            L += T_here * in_scatter * dt;
          }
          T *= step_T;
          return max_component(T) > 1e-6;
        });
  if (ctx_.has_environment) L += T * ctx_.environment;
  return L;
}

}  // namespace nimbus
