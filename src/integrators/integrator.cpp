#include "integrators/integrator.h"

#include <fmt/format.h>

#include "integrators/pathtrace.h"
#include "nimbus/error.h"

namespace nimbus {

SceneContext::SceneContext(const Scene& scene, int majorant_resolution, bool global_majorant)
    : media(scene.media),
      majorants(media, majorant_resolution, global_majorant),
      camera(scene.camera) {
  for (const Light& l : scene.lights) {
    if (const auto* env = std::get_if<EnvironmentLight>(&l)) {
      environment += env->radiance;
      has_environment = true;
    } else {
      lights.push_back(l);
    }
  }
}

std::unique_ptr<Integrator> make_integrator(const std::string& type, const IntegratorSettings& settings,
                                            const SceneContext& context) {
  if (type == "pathtrace") return std::make_unique<PathTracer>(context, settings.max_events);
  throw Error(fmt::format("unknown integrator '{}' (known: pathtrace)", type));
}

}  // namespace nimbus
