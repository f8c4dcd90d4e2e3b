// Light sampling for next-event estimation.
#pragma once

#include <limits>

#include "core/math.h"
#include "nimbus/scene.h"

namespace nimbus {

// A sampled connection to a light: direction of travel FROM the shading point TO the light, the
// distance to it (infinity for directional lights), and radiance / pdf (the estimate's weight).
struct LightSample {
  Vec3 wi;
  double distance = std::numeric_limits<double>::infinity();
  Rgb weight{0.0};
};

// Directional and point lights. (The environment is sampled through the phase function, so it is
// not handled here.) Returns false when the light contributes nothing.
bool sample_light(const Light& light, const Vec3& p, double u1, double u2, LightSample* out);

// Radiance of a directional light's disc (angular diameter > 0): irradiance / (pi sin^2(radius)).
Rgb directional_disc_radiance(const DirectionalLight& light);

}  // namespace nimbus
