#include "integrators/octave.h"

#include <cmath>

#include "core/json_reader.h"
#include "integrators/area_light_view.h"
#include "integrators/camera_layers.h"
#include "integrators/env_light.h"
#include "integrators/surface_light.h"
#include "integrators/tracking.h"
#include "media/phase.h"
#include "scene/lights.h"

namespace nimbus {

OctaveSettings octave_settings_from_json(const nlohmann::json& options, const std::string& where) {
  OctaveSettings s;
  JsonObject o(options, where, "/integrator");
  s.octaves = int(o.integer("octaves", 1, 32, s.octaves));
  s.a = o.number("a", 0.0, 1.0, s.a);
  s.b = o.number("b", 0.0, 1.0, s.b);
  s.c = o.number("c", 0.0, 1.0, s.c);
  s.tau_step = o.number("tau_step", 1e-4, 100.0, s.tau_step);
  s.shadow_map_resolution = int(o.integer("shadow_map_resolution", 8, 1024, s.shadow_map_resolution));
  o.finish();
  return s;
}

nlohmann::json to_json(const OctaveSettings& s) {
  return {{"octaves", s.octaves},
          {"a", s.a},
          {"b", s.b},
          {"c", s.c},
          {"tau_step", s.tau_step},
          {"shadow_map_resolution", s.shadow_map_resolution}};
}

Phase scale_phase_eccentricity(const Phase& phase, double scale) {
  if (const auto* hg = std::get_if<HgPhase>(&phase)) return HgPhase{hg->g * scale};
  if (const auto* d = std::get_if<DoubleHgPhase>(&phase))
    return DoubleHgPhase{d->g1 * scale, d->g2 * scale, d->w};
  if (std::holds_alternative<IsotropicPhase>(phase) || scale >= 1.0) return phase;
  // Blend towards isotropic: tabulate c P + (1 - c) / (4 pi).
  std::vector<double> theta, value;
  const int n = 2001;
  for (int i = 0; i < n; ++i) {
    const double u = double(i) / (n - 1), th = kPi * u * u;
    theta.push_back(th);
    value.push_back(scale * phase_eval(phase, std::cos(th)) + (1.0 - scale) / (4.0 * kPi));
  }
  return make_tabulated_phase("octave", theta, value);
}

OctaveIntegrator::OctaveIntegrator(const SceneContext& context, OctaveSettings settings)
    : ctx_(context), s_(settings) {
  for (int j = 0; j < s_.octaves; ++j) {
    phases_.emplace_back();
    for (int i = 0; i < ctx_.media.count(); ++i)
      phases_.back().push_back(scale_phase_eccentricity(ctx_.media.phase(i), std::pow(s_.c, j)));
  }
  for (const Light& l : ctx_.lights)  // (area lights: a token map, they march to a sampled point)
    maps_.emplace_back(ctx_.media, ctx_.majorants, l, is_area_light(l) ? 8 : s_.shadow_map_resolution, 0.05);
}

Rgb OctaveIntegrator::octave_scatter(int j, double bj, const Vec3& p, const Vec3& d, const MediumPoint& mp,
                                     const LightSamples& lights, Rng& rng) const {
  Rgb in_scatter(0.0);
  for (int i = 0; i < mp.count; ++i) {
    if (max_component(mp.sigma_s_i[i]) <= 0.0) continue;
    const Phase& phase = phases_[j][i];
    Rgb Li(0.0);
    // Directional and point lights through the shadow maps, T^(b^j).
    for (size_t l = 0; l < ctx_.lights.size(); ++l) {
      if (!lights.ok[l]) continue;
      const double f = phase_eval(phase, dot(d, lights.ls[l].wi));
      Rgb T;
      for (int c = 0; c < 3; ++c) T[c] = std::pow(std::max(float(lights.T[l][c]), 1e-30f), bj);
      Li += lights.ls[l].weight * f * T;
    }
    // The environment: marched transmittance T^(b^j); the constant one along one phase-sampled
    // direction, the image by MIS of a map- and a phase-sampled direction (integrators/env_light.h).
    auto env_T = [&](const Vec3& wi) {
      constexpr double kInf = std::numeric_limits<double>::infinity();
      const Rgb T =
          ctx_.surfaces.occluded(p, wi, kInf)
              ? Rgb(0.0)
              : marched_transmittance(ctx_.media, ctx_.majorants, p, wi, kInf, 0.25 / std::max(bj, 0.05));
      Rgb Tb;
      for (int c = 0; c < 3; ++c) Tb[c] = std::pow(std::max(T[c], 1e-300), bj);
      return Tb;
    };
    if (ctx_.constant_environment()) {
      const double u1 = rng.uniform(), u2 = rng.uniform();
      Li += ctx_.environment * env_T(phase_sample(phase, d, u1, u2));
    }
    if (ctx_.env_map) Li += medium_env_map_light(*ctx_.env_map, phase, d, rng, env_T);
    in_scatter += mp.sigma_s_i[i] * Li;
  }
  return in_scatter;
}

Rgb OctaveIntegrator::Li(const Ray& ray, Rng& rng, CameraSample* sample) const {
  const Rgb L = trace(ray, rng, sample, 1);
  if (!has_visible_area_lights(ctx_)) return L;
  const Rgb Le = visible_area_lights(ctx_, ray, rng, kSurfaceShadowStep);
  if (sample) sample->direct += Le;  // light straight from a light
  return L + Le;
}

void OctaveIntegrator::sample_lights(const Vec3& p, Rng& rng, LightSamples* lights) const {
  for (size_t l = 0; l < ctx_.lights.size(); ++l) {
    const double u1 = rng.uniform(), u2 = rng.uniform();
    LightSample& ls = lights->ls[l];
    bool ok = sample_light(ctx_.lights[l], p, u1, u2, &ls);
    if (ok && ctx_.surfaces.occluded(p, ls.wi, ls.distance)) ok = false;  // a surface shadows p
    if (ok && is_area_light(ctx_.lights[l]))  // the sampled point of an area light, marched
      lights->T[l] =
          marched_transmittance(ctx_.media, ctx_.majorants, p, ls.wi, ls.distance, kSurfaceShadowStep);
    else if (ok)
      lights->T[l] = maps_[l].lookup(p);
    lights->ok[l] = ok;
  }
}

Rgb OctaveIntegrator::trace(const Ray& ray, Rng& rng, CameraSample* sample, int bounces) const {
  const Vec3 &o = ray.o, &d = ray.d;
  SurfaceHit hit;
  const bool on_surface = ctx_.surfaces.intersect(o, d, std::numeric_limits<double>::infinity(), &hit);
  const int N = s_.octaves;
  std::vector<double> aj(N), bj(N);
  for (int j = 0; j < N; ++j) {
    aj[j] = std::pow(s_.a, j);
    bj[j] = std::pow(s_.b, j);
  }
  // Camera-side optical depth from the camera (octave j sees exp(-b^j tau)).
  Rgb L(0.0), tau(0.0), direct(0.0);  // direct: octave 0, the exact single scattering
  MarchRecorder layers(sample);
  const double jitter = rng.uniform();
  MediumPoint mp;
  LightSamples lights;
  lights.ls.resize(ctx_.lights.size());
  lights.T.resize(ctx_.lights.size());
  lights.ok.resize(ctx_.lights.size());
  march(ctx_.majorants, o, d, hit.t, s_.tau_step, jitter, [&](const Vec3& p, double t, double dt) {
    ctx_.media.eval(p, &mp);
    // Emission, seen through the true transmittance (octaves do not scatter it).
    Rgb L_step = ctx_.media.emits()
                     ? emission_over_step(mp.emission, exp(-tau), exp(-tau - mp.sigma_t() * dt), dt)
                     : Rgb(0.0);
    L += L_step;
    if (max_component(mp.sigma_s) > 0.0) {
      const Rgb tau_here = tau + mp.sigma_t() * (jitter * dt);
      sample_lights(p, rng, &lights);  // exp(-tau_l) once per light (octave j: raised to b^j)
      // Octave j: scattering a^j sigma_s seen through the camera-side transmittance exp(-b^j tau).
      for (int j = 0; j < N; ++j) {
        Rgb Tc;
        for (int c = 0; c < 3; ++c) Tc[c] = std::exp(-bj[j] * tau_here[c]);
        if (max_component(Tc) < 1e-7) continue;
        const Rgb Lj = Tc * octave_scatter(j, bj[j], p, d, mp, lights, rng) * (aj[j] * dt);
        L += Lj;
        L_step += Lj;
        if (j == 0) direct += Lj;
      }
    }
    const Rgb T0 = exp(-tau);
    tau += mp.sigma_t() * dt;
    layers.step(t - jitter * dt, dt, T0, exp(-tau), mp, L_step);
    return min_component(tau) * bj[N - 1] < 14.0;
  });
  // The surface the ray ends on (lit directly and by one gathered ray) or the environment.
  const GatherFn gather = [&](const Ray& r) { return trace(r, rng, nullptr, bounces - 1); };
  Rgb surface_direct;
  const Rgb L_end = ray_end_radiance(ctx_, on_surface ? &hit : nullptr, d, exp(-tau), rng, sample,
                                     bounces > 0 ? &gather : nullptr, &surface_direct, kSurfaceShadowStep);
  layers.finish(ctx_, d, on_surface ? Rgb(0.0) : exp(-tau), direct + surface_direct);
  return L + L_end;
}

}  // namespace nimbus
