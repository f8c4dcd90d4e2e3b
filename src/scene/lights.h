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

// What sample_light computes from the light alone, once per light (SceneContext::light_constants): a
// directional disc's cone and weight (two of the three trigonometric calls of each sample of a sun).
struct LightConstants {
  double cos_max = 1.0;  // directional disc: cosine of its angular radius
  Rgb disc_weight{0.0};  // directional disc: its radiance times the cone's solid angle 2 pi (1 - cos_max)
};
LightConstants light_constants(const Light& light);

// Directional, point, spot, sphere and rectangle lights. (The environment is sampled through the phase function, so it is
// not handled here.) Returns false when the light contributes nothing. With the light's constants
// (light_constants(light)) bit for bit the same sample, cheaper.
bool sample_light(const Light& light, const Vec3& p, double u1, double u2, LightSample* out);
bool sample_light(const Light& light, const LightConstants& k, const Vec3& p, double u1, double u2,
                  LightSample* out);

// A spot light's falloff at the cosine to its axis (docs/scene-format.md, "spot"): 0 outside the cone
// (half angle h = cone_angle_deg / 2), 1 inside away from the edge, and across the blended band
// cos(h) < cos < cos(h) + blend (1 - cos(h)) Cycles' smoothstep x^2 (3 - 2x), x = (cos - cos(h)) / (blend
// (1 - cos(h))). No cosine-to-axis factor (Cycles 3.4 multiplies by it).
double spot_falloff(const SpotLight& s, double cos_to_axis);

// The direction (unit, from p) and distance to a light's centre, the one point a shadow map marches to:
// a directional light's direction (infinitely far), a point or spot light's position, an area light's
// centre. False for the environment and when p is at the light.
bool light_centre(const Light& light, const Vec3& p, Vec3* wi, double* distance);

// Sphere and rectangle lights: their shadows are soft, so the integrators that keep a transmittance
// grid per light sample a point of the light instead (scene/area_lights.h).
inline bool is_area_light(const Light& light) {
  return std::holds_alternative<SphereLight>(light) || std::holds_alternative<RectangleLight>(light);
}

// Radiance of a directional light's disc (angular diameter > 0): irradiance / (pi sin^2(radius)).
Rgb directional_disc_radiance(const DirectionalLight& light);

}  // namespace nimbus
