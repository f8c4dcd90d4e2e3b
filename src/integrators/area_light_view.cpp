// The visible area lights (integrators/area_light_view.h).
#include "integrators/area_light_view.h"

#include <limits>

#include "integrators/surface_light.h"
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

Rgb visible_area_lights(const SceneContext& ctx, const Ray& ray, Rng& rng, double march_step) {
  Rgb L(0.0);
  for (const Light& light : ctx.lights) {
    double t = 0.0;
    Rgb Le;
    if (!is_visible(light) ||
        !hit_area_light(light, ray.o, ray.d, std::numeric_limits<double>::infinity(), &t, &Le))
      continue;
    L += Le * shadow_transmittance(ctx, ray.o, ray.d, t, rng, march_step);
  }
  return L;
}

}  // namespace nimbus
