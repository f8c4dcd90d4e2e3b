// The integrator registry: one entry per integrator with its name, a one-line summary, the strict
// parser of its settings (the integrator block's own fields) and its constructor. The scene parser
// validates an integrator block through it, the driver constructs through it; nothing else lists the
// integrators. Adding an integrator: docs/architecture.md.
#pragma once

#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "integrators/integrator.h"
#include "nimbus/scene.h"

namespace nimbus {

struct IntegratorEntry {
  std::string name;
  std::string summary;
  // Checks the integrator-specific fields of an integrator block (strict: unknown keys, values out of
  // range and conflicting fields are nimbus::Errors "WHERE: /integrator/KEY: message").
  std::function<void(const nlohmann::json& options, const std::string& where)> validate;
  // Parses settings.options (strictly, as validate) and builds the integrator for the scene.
  std::function<std::unique_ptr<Integrator>(const SceneContext& context, const IntegratorSettings& settings,
                                            const std::string& where)>
      make;
};

// Every integrator, in the order `nimbus render --help` lists them.
const std::vector<IntegratorEntry>& integrator_registry();
// The entry called `name`; a nimbus::Error listing the known names otherwise.
const IntegratorEntry& find_integrator(const std::string& name);

// Shorthands for the two calls through the registry.
void validate_integrator_options(const std::string& type, const nlohmann::json& options,
                                 const std::string& where);
std::unique_ptr<Integrator> make_integrator(const SceneContext& context, const IntegratorSettings& settings,
                                            const std::string& where = "scene");

}  // namespace nimbus
