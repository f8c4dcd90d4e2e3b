#include "integrators/integrator.h"

#include <fmt/format.h>

#include "integrators/mfs.h"
#include "integrators/octave.h"
#include "integrators/pathtrace.h"
#include "integrators/single.h"
#include "nimbus/error.h"
#include "nimbus/render.h"

namespace nimbus {

SceneContext::SceneContext(const Scene& scene, int majorant_resolution, bool global_majorant)
    : media(scene.media), majorants(media, majorant_resolution, global_majorant), camera(scene.camera) {
  for (const Light& l : scene.lights) {
    if (const auto* env = std::get_if<EnvironmentLight>(&l)) {
      environment += env->radiance;
      has_environment = true;
    } else {
      lights.push_back(l);
    }
  }
}

void validate_integrator_options(const std::string& type, const nlohmann::json& options,
                                 const std::string& where) {
  if (type == "pathtrace") {
    parse_pathtrace_settings(options, where, true);
  } else if (type == "single") {
    parse_single_settings(options, where, true);
  } else if (type == "mfs") {
    parse_mfs_settings(options, where, true);
  } else if (type == "octave") {
    parse_octave_settings(options, where, true);
  } else if (!options.empty()) {
    throw Error(fmt::format("{}: /integrator/{}: unknown field for integrator '{}'", where,
                            options.begin().key(), type));
  }
}

std::unique_ptr<Integrator> make_integrator(const std::string& type, const IntegratorSettings& settings,
                                            const SceneContext& context) {
  if (type == "pathtrace")
    return std::make_unique<PathTracer>(context, settings.max_events,
                                        parse_pathtrace_settings(settings.options, "scene", false));
  if (type == "single")
    return std::make_unique<SingleScatter>(context, parse_single_settings(settings.options, "scene", false));
  if (type == "mfs")
    return std::make_unique<MfsIntegrator>(
        context, parse_mfs_settings(settings.options, "scene", false, settings.seed));
  if (type == "octave")
    return std::make_unique<OctaveIntegrator>(context,
                                              parse_octave_settings(settings.options, "scene", false));
  throw Error(fmt::format("unknown integrator '{}' (known: {})", type, fmt::join(integrator_names(), ", ")));
}

}  // namespace nimbus
