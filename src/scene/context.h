// What every integrator shares for one render: the media with their majorant grid, the surfaces, the camera and the
// lights (directional and point lights for next-event estimation; the environment as one radiance).
#pragma once

#include <vector>

#include "core/math.h"
#include "media/majorant.h"
#include "media/media.h"
#include "nimbus/scene.h"
#include "scene/camera.h"
#include "scene/surfaces.h"

namespace nimbus {

struct SceneContext {
  explicit SceneContext(const Scene& scene, int majorant_resolution = 0, bool global_majorant = false);
  SceneMedia media;
  MajorantGrid majorants;
  SceneSurfaces surfaces;
  PinholeCamera camera;
  std::vector<Light> lights;  // every light but the environment (sampled by NEE)
  Rgb environment{0.0};       // sum of environment lights' radiance
  bool has_environment = false;
};

}  // namespace nimbus
