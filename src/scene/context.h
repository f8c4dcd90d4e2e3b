// What every integrator shares for one render: the media with their majorant grid, the surfaces, the camera and the
// lights (directional and point lights for next-event estimation; the environment as one radiance).
#pragma once

#include <memory>
#include <vector>

#include "core/math.h"
#include "media/analytic_media.h"
#include "media/majorant.h"
#include "media/media.h"
#include "nimbus/scene.h"
#include "scene/camera.h"
#include "scene/env_map.h"
#include "scene/lights.h"
#include "scene/surfaces.h"

namespace nimbus {

struct SceneContext {
  explicit SceneContext(const Scene& scene, int majorant_resolution = 0, bool global_majorant = false);
  SceneMedia media;
  MajorantGrid majorants;
  AnalyticMedia
      analytic;  // active when every medium is a constant-density sphere or box (media/analytic_media.h)
  SceneSurfaces surfaces;
  PinholeCamera camera;
  std::vector<Light> lights;                    // every light but the environment (sampled by NEE)
  std::vector<LightConstants> light_constants;  // per light: what sample_light needs from it alone
  Rgb environment{0.0};                         // sum of constant environment lights' radiance
  bool has_environment = false;
  std::shared_ptr<const EnvMap> env_map;  // the environment image, if any (scene/env_map.h)

  // The environment's radiance arriving from the world direction w (unit): the constant part plus the image's.
  Rgb environment_radiance(const Vec3& w) const {
    return env_map ? environment + env_map->eval(w) : environment;
  }
  // Whether the constant part is sampled on its own (through the phase function or the cosine): always
  // with a constant environment light, and with an image only where a constant light is added to it.
  bool constant_environment() const {
    return has_environment && (!env_map || max_component(environment) > 0.0);
  }
};

}  // namespace nimbus
