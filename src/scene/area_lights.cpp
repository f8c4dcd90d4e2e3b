// The sphere and rectangle area lights (scene/area_lights.h).
#include "scene/area_lights.h"

#include <cmath>

#include "scene/lights.h"

namespace nimbus {

bool sample_sphere_light(const SphereLight& s, const Vec3& p, double u1, double u2, LightSample* out) {
  const Vec3 v = s.center - p;
  const double d2 = v.length2(), r2 = s.radius * s.radius;
  if (!(d2 > r2)) return false;  // inside (or on) the sphere: it emits outward only
  const double d = std::sqrt(d2);
  // The cap's cone: sin^2(alpha) = r^2 / d^2; 1 - cos_max written without cancellation.
  const double sin2 = r2 / d2, cos_max = std::sqrt(1.0 - sin2);
  const double one_minus_cos_max = sin2 / (1.0 + cos_max);
  const double one_minus_cos = u1 * one_minus_cos_max;
  const double cos_theta = 1.0 - one_minus_cos;
  out->wi = spherical_direction(cos_theta, 2.0 * kPi * u2, v / d);
  // The near intersection along wi: t = d cos - sqrt(r^2 - d^2 sin^2).
  const double sin2_theta = one_minus_cos * (2.0 - one_minus_cos);
  out->distance = d * cos_theta - std::sqrt(std::max(0.0, r2 - d2 * sin2_theta));
  out->weight = s.radiance * (2.0 * kPi * one_minus_cos_max);  // L / pdf
  return true;
}

bool sample_rectangle_light(const RectangleLight& r, const Vec3& p, double u1, double u2, LightSample* out) {
  const Vec3 q = r.center + rectangle_width_axis(r) * ((u1 - 0.5) * r.width) + r.up * ((u2 - 0.5) * r.height);
  const Vec3 v = q - p;
  const double dist2 = v.length2();
  if (!(dist2 > 0.0)) return false;
  const double dist = std::sqrt(dist2);
  const Vec3 wi = v / dist;
  const double cos_l = -dot(wi, r.normal);  // the light's cosine at q towards p
  if (cos_l <= 0.0) return false;           // p behind the emitting side
  out->wi = wi;
  out->distance = dist;
  out->weight = r.radiance * (r.width * r.height * cos_l / dist2);  // L / pdf, pdf = d^2 / (A cos_l)
  return true;
}

bool hit_area_light(const Light& light, const Vec3& o, const Vec3& d, double tmax, double* t, Rgb* L) {
  if (const auto* s = std::get_if<SphereLight>(&light)) {
    const Vec3 oc = o - s->center;
    const double b = dot(oc, d), c = oc.length2() - s->radius * s->radius;
    if (c <= 0.0) return false;  // from inside: the sphere emits outward only
    const double disc = b * b - c;
    if (disc < 0.0) return false;
    const double t0 = -b - std::sqrt(disc);
    if (!(t0 > 0.0 && t0 < tmax)) return false;
    *t = t0;
    *L = s->radiance;
    return true;
  }
  if (const auto* r = std::get_if<RectangleLight>(&light)) {
    const double dn = dot(d, r->normal);
    if (dn >= 0.0) return false;  // the back or the edge: nothing is emitted that way
    const double t0 = dot(r->center - o, r->normal) / dn;
    if (!(t0 > 0.0 && t0 < tmax)) return false;
    const Vec3 q = o + d * t0 - r->center;
    if (std::abs(dot(q, rectangle_width_axis(*r))) > 0.5 * r->width ||
        std::abs(dot(q, r->up)) > 0.5 * r->height)
      return false;
    *t = t0;
    *L = r->radiance;
    return true;
  }
  return false;
}

bool emit_area_photon(const Light& light, double count, double u1, double u2, double u3, double u4, Vec3* x,
                      Vec3* w, Rgb* power) {
  if (const auto* s = std::get_if<SphereLight>(&light)) {
    const Vec3 n = spherical_direction(1.0 - 2.0 * u1, 2.0 * kPi * u2, Vec3(0, 0, 1));
    *x = s->center + n * s->radius;
    *w = cosine_direction(n, u3, u4);
    *power = s->radiance * (4.0 * kPi * kPi * s->radius * s->radius / count);
    return true;
  }
  if (const auto* r = std::get_if<RectangleLight>(&light)) {
    *x = r->center + rectangle_width_axis(*r) * ((u1 - 0.5) * r->width) + r->up * ((u2 - 0.5) * r->height);
    *w = cosine_direction(r->normal, u3, u4);
    *power = r->radiance * (kPi * r->width * r->height / count);
    return true;
  }
  return false;
}

}  // namespace nimbus
