#include "scene/context.h"

namespace nimbus {

SceneContext::SceneContext(const Scene& scene, int majorant_resolution, bool global_majorant)
    : media(scene.media),
      majorants(media, majorant_resolution, global_majorant),
      analytic(media),
      surfaces(scene.surfaces),
      camera(scene.camera) {
  for (const Light& l : scene.lights) {
    if (const auto* env = std::get_if<EnvironmentLight>(&l)) {
      environment += env->radiance;
      has_environment = true;
      if (env->map) env_map = env->map;  // the parser allows one image per scene
    } else {
      lights.push_back(l);
      light_constants.push_back(nimbus::light_constants(l));
    }
  }
}

}  // namespace nimbus
