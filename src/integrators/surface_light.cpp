// Light at surfaces (integrators/surface_light.h).
#include "integrators/surface_light.h"

#include "integrators/env_light.h"
#include "integrators/shadow_map.h"
#include "integrators/tracking.h"
#include "scene/lights.h"

namespace nimbus {

namespace {
// Set while a surface gathers its one ray (surface_radiance with a gather) in a scene with an environment
// image: that surface took the image's light by MIS already, so the gathered ray's escape shows only the
// constant environment. Per thread: an integrator's Li runs on one thread, the gather inside it.
thread_local bool t_env_map_taken = false;
struct EnvMapTakenHere {
  bool saved;
  explicit EnvMapTakenHere(bool taken) : saved(t_env_map_taken) { t_env_map_taken = taken; }
  ~EnvMapTakenHere() { t_env_map_taken = saved; }
};
}  // namespace

Rgb shadow_transmittance(const SceneContext& ctx, const Vec3& p, const Vec3& w, double tmax, Rng& rng,
                         double march_step) {
  if (ctx.surfaces.occluded(p, w, tmax)) return Rgb(0.0);
  if (march_step > 0.0) return marched_transmittance(ctx.media, ctx.majorants, p, w, tmax, march_step);
  // Constant-density shapes: the closed form exp(-sigma_t x chord), exact and free of noise.
  if (ctx.analytic.active()) return ctx.analytic.transmittance(p, w, tmax);
  return ratio_tracking_transmittance(ctx.media, ctx.majorants, p, w, tmax, rng);
}

Rgb surface_direct_light(const SceneContext& ctx, const SurfaceHit& hit, const Rgb& albedo, Rng& rng,
                         double march_step, const PathClock* timed) {
  Rgb E(0.0);  // cosine-weighted irradiance / pi
  for (const Light& light : ctx.lights) {
    LightSample ls;
    const double u1 = rng.uniform(), u2 = rng.uniform();
    if (!sample_light(light, hit.p, u1, u2, &ls)) continue;
    const double cos_theta = dot(hit.ns, ls.wi);
    if (cos_theta <= 0.0 || dot(hit.ng, ls.wi) <= 0.0) continue;
    const Vec3 o = SceneSurfaces::offset(hit, ls.wi);
    const Rgb e =
        ls.weight * shadow_transmittance(ctx, o, ls.wi, ls.distance, rng, march_step) * (cos_theta / kPi);
    E += e;
    if (timed) timed->record(timed->connection(hit.p, ls), albedo * e);
  }
  return albedo * E;
}

Rgb surface_radiance(const SceneContext& ctx, const SurfaceHit& hit, Rng& rng, const GatherFn* gather,
                     Rgb* direct_part, double march_step, const PathClock* timed) {
  const auto* diffuse = std::get_if<DiffuseMaterial>(&ctx.surfaces.material(hit.surface));
  if (!diffuse) return Rgb(0.0);  // a holdout
  Rgb L = surface_direct_light(ctx, hit, diffuse->albedo, rng, march_step, timed);
  if (direct_part) *direct_part = L;
  if (!gather && !ctx.has_environment) return L;
  // The environment image by MIS (integrators/env_light.h); a gathered ray then leaves it out where it
  // escapes (EnvMapTakenHere), so that it is counted once.
  if (ctx.env_map) L += diffuse->albedo * surface_env_map_light(ctx, hit, rng, march_step);
  if (!gather && !ctx.constant_environment()) return L;
  const double u1 = rng.uniform(), u2 = rng.uniform();
  const Vec3 wi = cosine_direction(hit.ns, u1, u2);
  if (dot(hit.ng, wi) <= 0.0) return L;
  const Vec3 o = SceneSurfaces::offset(hit, wi);
  if (gather) {
    const EnvMapTakenHere taken(ctx.env_map != nullptr);
    return L + diffuse->albedo * (*gather)(Ray{o, wi});
  }
  const Rgb env = diffuse->albedo * ctx.environment *
                  shadow_transmittance(ctx, o, wi, std::numeric_limits<double>::infinity(), rng, march_step);
  if (timed) timed->record(timed->distant.distance(hit.p, wi), env);
  return L + env;
}

Rgb surface_env_map_light(const SceneContext& ctx, const SurfaceHit& hit, Rng& rng, double march_step) {
  const double u1 = rng.uniform(), u2 = rng.uniform(), v1 = rng.uniform(), v2 = rng.uniform();
  // Lit on the viewer's side only (the shading and the geometric normal agree), cos / pi per unit albedo.
  auto cosine_pdf = [&](const Vec3& wi) {
    return dot(hit.ng, wi) > 0.0 ? std::max(0.0, dot(hit.ns, wi)) / kPi : 0.0;
  };
  return env_map_mis(
      *ctx.env_map, u1, u2, cosine_direction(hit.ns, v1, v2),
      [&](const Vec3& wi) { return Rgb(cosine_pdf(wi)); }, cosine_pdf,
      [&](const Vec3& wi) {
        return shadow_transmittance(ctx, SceneSurfaces::offset(hit, wi), wi,
                                    std::numeric_limits<double>::infinity(), rng, march_step);
      });
}

Rgb ray_end_radiance(const SceneContext& ctx, const SurfaceHit* hit, const Vec3& d, const Rgb& T, Rng& rng,
                     CameraSample* sample, const GatherFn* gather, Rgb* direct_part, double march_step) {
  if (direct_part) *direct_part = Rgb(0.0);
  if (!hit) {
    if (!ctx.has_environment) return Rgb(0.0);
    return T * (t_env_map_taken ? ctx.environment : ctx.environment_radiance(d));
  }
  if (sample) record_surface_hit(ctx, *hit, T, sample);
  if (max_component(T) <= 0.0) return Rgb(0.0);
  Rgb direct(0.0);
  const Rgb L = T * surface_radiance(ctx, *hit, rng, gather, &direct, march_step);
  if (direct_part) *direct_part = T * direct;
  const bool diffuse = std::holds_alternative<DiffuseMaterial>(ctx.surfaces.material(hit->surface));
  if (sample && sample->deep && diffuse) sample->deep->push_back({hit->t, hit->t, L, average(T)});
  return L;
}

void record_surface_hit(const SceneContext& ctx, const SurfaceHit& hit, const Rgb& T, CameraSample* sample) {
  sample->escape_transmittance = Rgb(0.0);
  sample->normal = hit.ns;
  const auto* diffuse = std::get_if<DiffuseMaterial>(&ctx.surfaces.material(hit.surface));
  if (!diffuse) sample->holdout_transmittance = T;
  if (std::isfinite(sample->depth)) return;  // the media in front hold the depth
  sample->depth = hit.t;
  sample->albedo = diffuse ? diffuse->albedo : Rgb(0.0);
}

}  // namespace nimbus
