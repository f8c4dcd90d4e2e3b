// Integrators: an open set behind one virtual call per camera ray. Each holds what it precomputed for
// the scene (shadow maps, photon grids); Li() is called concurrently from many threads. The driver
// (src/render/render.cpp) makes the camera rays and owns the film; the registry
// (integrators/registry.h) parses each integrator's settings and constructs it.
#pragma once

#include <nlohmann/json.hpp>

#include "core/math.h"
#include "core/ray.h"
#include "core/rng.h"
#include "scene/context.h"

namespace nimbus {

class Integrator {
 public:
  virtual ~Integrator() = default;
  // Radiance arriving at ray.o from direction -ray.d (light travelling against the ray).
  virtual Rgb Li(const Ray& ray, Rng& rng) const = 0;
  // The integrator's own settings as the JSON fields of its integrator block, with "auto" choices
  // resolved: written into the image header, so that an image says exactly how it was made.
  virtual nlohmann::json settings_json() const = 0;
};

}  // namespace nimbus
