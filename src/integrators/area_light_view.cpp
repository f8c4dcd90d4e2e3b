// The visible area lights (integrators/area_light_view.h).
#include "integrators/area_light_view.h"

#include <limits>

#include "integrators/surface_light.h"
#include "integrators/tracking.h"
#include "scene/area_lights.h"

namespace nimbus {

namespace {
bool is_visible(const Light& light) {
  if (const auto* s = std::get_if<SphereLight>(&light)) return s->visible;
  if (const auto* r = std::get_if<RectangleLight>(&light)) return r->visible;
  return false;
}
}  // namespace

bool has_visible_area_lights(const SceneContext& ctx) {
  for (const Light& light : ctx.lights)
    if (is_visible(light)) return true;
  return false;
}

Rgb visible_area_lights(const SceneContext& ctx, const Ray& ray, Rng& rng, double march_step,
                        std::vector<TimedContribution>* timed) {
  Rgb L(0.0);
  for (const Light& light : ctx.lights) {
    double t = 0.0;
    Rgb Le;
    if (!is_visible(light) ||
        !hit_area_light(light, ray.o, ray.d, std::numeric_limits<double>::infinity(), &t, &Le))
      continue;
    const Rgb c = Le * shadow_transmittance(ctx, ray.o, ray.d, t, rng, march_step);
    L += c;
    if (timed) timed->push_back({t * length(ray.d), c, false});
  }
  return L;
}

void marched_full_and_reduced(const SceneContext& ctx, const Vec3& p, const Vec3& w, double tmax,
                              double tau_step, const std::vector<double>& peak_fraction, Rgb* T_full,
                              Rgb* T_reduced) {
  Rgb tau(0.0), tau_reduced(0.0);
  MediumPoint mp;
  march(ctx.majorants, p, w, tmax, tau_step, 0.5, [&](const Vec3& x, double, double dt) {
    ctx.media.eval(x, &mp);
    Rgb reduced = mp.sigma_t();
    tau += reduced * dt;
    for (int i = 0; i < mp.count && i < int(peak_fraction.size()); ++i)
      reduced -= mp.sigma_s_i[i] * peak_fraction[i];
    tau_reduced += reduced * dt;
    return min_component(tau_reduced) < 50.0;
  });
  *T_full = exp_channels(-tau);
  *T_reduced = exp_channels(-tau_reduced);
}

bool chord_full_and_reduced(const SceneContext& ctx, const Vec3& p, const Vec3& w, double tmax,
                            const std::vector<double>& peak_fraction, Rgb* T_full, Rgb* T_reduced) {
  if (!ctx.analytic.active() || ctx.media.count() != 1) return false;
  double t0 = 0.0, t1 = 0.0;
  if (!ctx.analytic.chord(0, p, w, tmax, &t0, &t1) || !(t1 > t0)) {
    *T_full = *T_reduced = Rgb(1.0);
    return true;
  }
  MediumPoint m;
  ctx.media.eval(p + w * (0.5 * (t0 + t1)), &m);
  const Rgb sigma_t = m.sigma_t();
  const Rgb sigma_red = peak_fraction.empty() ? sigma_t : sigma_t - m.sigma_s_i[0] * peak_fraction[0];
  *T_full = exp_channels(-sigma_t * (t1 - t0));
  *T_reduced = exp_channels(-sigma_red * (t1 - t0));
  return true;
}

}  // namespace nimbus
