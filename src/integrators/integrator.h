// Integrators: an open set behind one virtual call per camera sample. Each holds what it
// precomputed for the scene; sample() is called concurrently from many threads.
#pragma once

#include <memory>
#include <string>

#include "core/math.h"
#include "core/rng.h"
#include "media/majorant.h"
#include "media/media.h"
#include "nimbus/scene.h"
#include "render/camera.h"

namespace nimbus {

// What every integrator shares: the media, their majorant grid, the camera and the lights.
struct SceneContext {
  explicit SceneContext(const Scene& scene, int majorant_resolution = 0, bool global_majorant = false);
  SceneMedia media;
  MajorantGrid majorants;
  PinholeCamera camera;
  std::vector<Light> lights;  // directional and point lights (sampled by NEE)
  Rgb environment{0.0};       // sum of environment lights' radiance
  bool has_environment = false;
};

class Integrator {
 public:
  virtual ~Integrator() = default;
  // Radiance estimate along the camera ray through image point (px, py) (pixels, continuous).
  virtual Rgb sample(double px, double py, Rng& rng) const = 0;
};

// Checks the integrator-specific fields of a scene's integrator block (errors name `where`).
void validate_integrator_options(const std::string& type, const nlohmann::json& options,
                                 const std::string& where);

std::unique_ptr<Integrator> make_integrator(const std::string& type, const IntegratorSettings& settings,
                                            const SceneContext& context);

}  // namespace nimbus
