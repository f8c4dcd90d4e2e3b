#include "scene/lights.h"

namespace nimbus {

Rgb directional_disc_radiance(const DirectionalLight& light) {
  const double radius = 0.5 * light.angular_diameter_deg * kPi / 180.0;
  const double s = std::sin(radius);
  return light.irradiance / (kPi * s * s);
}

bool sample_light(const Light& light, const Vec3& p, double u1, double u2, LightSample* out) {
  if (const auto* d = std::get_if<DirectionalLight>(&light)) {
    const Vec3 to_light = -d->direction;
    out->distance = std::numeric_limits<double>::infinity();
    if (d->angular_diameter_deg <= 0.0) {
      out->wi = to_light;
      out->weight = d->irradiance;
      return true;
    }
    // Uniform in the cone of the disc: weight = L / pdf = L * 2 pi (1 - cos r).
    const double radius = 0.5 * d->angular_diameter_deg * kPi / 180.0;
    const double cos_max = std::cos(radius);
    const double cos_theta = 1.0 - u1 * (1.0 - cos_max);
    out->wi = spherical_direction(cos_theta, 2.0 * kPi * u2, to_light);
    out->weight = directional_disc_radiance(*d) * (2.0 * kPi * (1.0 - cos_max));
    return true;
  }
  if (const auto* pt = std::get_if<PointLight>(&light)) {
    const Vec3 v = pt->position - p;
    const double dist2 = v.length2();
    if (!(dist2 > 0.0)) return false;
    out->distance = std::sqrt(dist2);
    out->wi = v / out->distance;
    out->weight = pt->intensity / dist2;
    return true;
  }
  return false;
}

}  // namespace nimbus
