#include "scene/lights.h"

#include "scene/area_lights.h"

namespace nimbus {

Rgb directional_disc_radiance(const DirectionalLight& light) {
  const double radius = 0.5 * light.angular_diameter_deg * kPi / 180.0;
  const double s = std::sin(radius);
  return light.irradiance / (kPi * s * s);
}

LightConstants light_constants(const Light& light) {
  LightConstants k;
  if (const auto* d = std::get_if<DirectionalLight>(&light); d && d->angular_diameter_deg > 0.0) {
    // Uniform in the cone of the disc: weight = L / pdf = L * 2 pi (1 - cos r).
    const double radius = 0.5 * d->angular_diameter_deg * kPi / 180.0;
    k.cos_max = std::cos(radius);
    k.disc_weight = directional_disc_radiance(*d) * (2.0 * kPi * (1.0 - k.cos_max));
  }
  return k;
}

bool sample_light(const Light& light, const Vec3& p, double u1, double u2, LightSample* out) {
  return sample_light(light, light_constants(light), p, u1, u2, out);
}

bool sample_light(const Light& light, const LightConstants& k, const Vec3& p, double u1, double u2,
                  LightSample* out) {
  if (const auto* d = std::get_if<DirectionalLight>(&light)) {
    const Vec3 to_light = -d->direction;
    out->distance = std::numeric_limits<double>::infinity();
    if (d->angular_diameter_deg <= 0.0) {
      out->wi = to_light;
      out->weight = d->irradiance;
      return true;
    }
    // Uniform in the cone of the disc (light_constants).
    const double cos_theta = 1.0 - u1 * (1.0 - k.cos_max);
    out->wi = spherical_direction(cos_theta, 2.0 * kPi * u2, to_light);
    out->weight = k.disc_weight;
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
  if (const auto* sp = std::get_if<SpotLight>(&light)) {
    const Vec3 v = sp->position - p;
    const double dist2 = v.length2();
    if (!(dist2 > 0.0)) return false;
    out->distance = std::sqrt(dist2);
    out->wi = v / out->distance;
    const double falloff = spot_falloff(*sp, -dot(out->wi, sp->direction));
    if (falloff <= 0.0) return false;
    out->weight = sp->intensity * (falloff / dist2);
    return true;
  }
  if (const auto* s = std::get_if<SphereLight>(&light)) return sample_sphere_light(*s, p, u1, u2, out);
  if (const auto* r = std::get_if<RectangleLight>(&light)) return sample_rectangle_light(*r, p, u1, u2, out);
  return false;
}

double spot_falloff(const SpotLight& s, double cos_to_axis) {
  const double cos_half = std::cos(0.5 * s.cone_angle_deg * kPi / 180.0);
  if (cos_to_axis <= cos_half) return 0.0;
  const double band = s.blend * (1.0 - cos_half), t = cos_to_axis - cos_half;
  if (t >= band) return 1.0;
  const double x = t / band;
  return x * x * (3.0 - 2.0 * x);
}

bool light_centre(const Light& light, const Vec3& p, Vec3* wi, double* distance) {
  Vec3 at;
  if (const auto* d = std::get_if<DirectionalLight>(&light)) {
    *wi = -d->direction;
    *distance = std::numeric_limits<double>::infinity();
    return true;
  } else if (const auto* pt = std::get_if<PointLight>(&light)) {
    at = pt->position;
  } else if (const auto* sp = std::get_if<SpotLight>(&light)) {
    at = sp->position;
  } else if (const auto* s = std::get_if<SphereLight>(&light)) {
    at = s->center;
  } else if (const auto* r = std::get_if<RectangleLight>(&light)) {
    at = r->center;
  } else {
    return false;
  }
  *distance = length(at - p);
  if (!(*distance > 0.0)) return false;
  *wi = (at - p) / *distance;
  return true;
}

}  // namespace nimbus
