#include "integrators/registry.h"

#include <fmt/format.h>

#include "integrators/mfs.h"
#include "integrators/octave.h"
#include "integrators/pathtrace.h"
#include "integrators/single.h"
#include "nimbus/error.h"
#include "nimbus/render.h"

namespace nimbus {

namespace {

// An entry from a settings parser and a constructor taking (context, settings, the block's common fields).
template <typename Settings, typename Build>
IntegratorEntry entry(std::string name, std::string summary,
                      Settings (*parse)(const nlohmann::json&, const std::string&), Build build) {
  IntegratorEntry e;
  e.name = std::move(name);
  e.summary = std::move(summary);
  e.validate = [parse](const nlohmann::json& options, const std::string& where) { parse(options, where); };
  e.make = [parse, build](const SceneContext& context, const IntegratorSettings& settings,
                          const std::string& where) -> std::unique_ptr<Integrator> {
    return build(context, parse(settings.options, where), settings);
  };
  return e;
}

std::vector<IntegratorEntry> make_registry() {
  std::vector<IntegratorEntry> r;
  r.push_back(entry("pathtrace", "the reference: unbiased volumetric path tracing",
                    &pathtrace_settings_from_json,
                    [](const SceneContext& c, PathTraceSettings s, const IntegratorSettings& common) {
                      return std::make_unique<PathTracer>(c, common.max_events, s);
                    }));
  r.push_back(entry("single", "unscattered plus single-scattered light by a ray march",
                    &single_settings_from_json,
                    [](const SceneContext& c, SingleSettings s, const IntegratorSettings&) {
                      return std::make_unique<SingleScatter>(c, s);
                    }));
  r.push_back(entry("mfs", "the multiple-forward-scattering model (the seed paper, completed)",
                    &mfs_settings_from_json,
                    [](const SceneContext& c, MfsSettings s, const IntegratorSettings& common) {
                      return std::make_unique<MfsIntegrator>(c, s, common.seed);
                    }));
  r.push_back(entry(
      "octave", "the production baseline of Wrenninge et al. 2013 (octaves of single scattering)",
      &octave_settings_from_json, [](const SceneContext& c, OctaveSettings s, const IntegratorSettings&) {
        return std::make_unique<OctaveIntegrator>(c, s);
      }));
  return r;
}

}  // namespace

const std::vector<IntegratorEntry>& integrator_registry() {
  static const std::vector<IntegratorEntry> registry = make_registry();
  return registry;
}

const IntegratorEntry& find_integrator(const std::string& name) {
  for (const IntegratorEntry& e : integrator_registry())
    if (e.name == name) return e;
  throw Error(fmt::format("unknown integrator '{}' (known: {})", name, fmt::join(integrator_names(), ", ")));
}

std::vector<std::string> integrator_names() {
  std::vector<std::string> names;
  for (const IntegratorEntry& e : integrator_registry()) names.push_back(e.name);
  return names;
}

void validate_integrator_options(const std::string& type, const nlohmann::json& options,
                                 const std::string& where) {
  find_integrator(type).validate(options, where);
}

std::unique_ptr<Integrator> make_integrator(const SceneContext& context, const IntegratorSettings& settings,
                                            const std::string& where) {
  return find_integrator(settings.type).make(context, settings, where);
}

}  // namespace nimbus
