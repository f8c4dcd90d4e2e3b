// The sphere and rectangle area lights (scene/area_lights.h).
#include "scene/area_lights.h"

#include <algorithm>
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

namespace {

// Below this solid angle (sr) the rectangle is sampled by area: the spherical rectangle's angles lose
// their precision to cancellation there, and area sampling is as good as solid angle sampling when the
// light is small and far.
constexpr double kMinSolidAngle = 1e-3;

// The rectangle's corner (-w/2, -h/2) and its edges as vectors.
struct RectangleFrame {
  Vec3 corner, ex, ey;  // ex, ey unit
  double w, h;
};
RectangleFrame rectangle_frame(const RectangleLight& r) {
  const Vec3 ex = rectangle_width_axis(r);
  return {r.center - ex * (0.5 * r.width) - r.up * (0.5 * r.height), ex, r.up, r.width, r.height};
}

// Uniform sampling of the solid angle a rectangle subtends at o (Urena, Fajardo and King 2013, "An
// Area-Preserving Parametrization for Spherical Rectangles", section 3, written from the paper): the
// point of the rectangle for (u1, u2) and the solid angle S (the pdf is 1 / S). False when S is below
// kMinSolidAngle.
bool sample_spherical_rectangle(const RectangleFrame& f, const Vec3& o, double u1, double u2, Vec3* q,
                                double* solid_angle) {
  Vec3 z = cross(f.ex, f.ey);
  const Vec3 d = f.corner - o;
  double z0 = dot(d, z);
  if (z0 > 0.0) z0 = -z0, z = -z;  // the local frame's z points away from the rectangle
  const double x0 = dot(d, f.ex), y0 = dot(d, f.ey), x1 = x0 + f.w, y1 = y0 + f.h;
  const Vec3 v00(x0, y0, z0), v01(x0, y1, z0), v10(x1, y0, z0), v11(x1, y1, z0);
  // The normals of the four planes through o and an edge, and the spherical rectangle's inner angles.
  const Vec3 n0 = normalize(cross(v00, v10)), n1 = normalize(cross(v10, v11));
  const Vec3 n2 = normalize(cross(v11, v01)), n3 = normalize(cross(v01, v00));
  const auto angle = [](const Vec3& a, const Vec3& b) {
    return std::acos(std::clamp(-dot(a, b), -1.0, 1.0));
  };
  const double g0 = angle(n0, n1), g1 = angle(n1, n2), g2 = angle(n2, n3), g3 = angle(n3, n0);
  const double k = 2.0 * kPi - g2 - g3, S = g0 + g1 - k;
  if (!(S > kMinSolidAngle)) return false;
  // The x coordinate from u1 (eq. 13 - 16 of the paper), then y from u2 (eq. 17 - 18).
  const double b0 = n0.z, b1 = n2.z, au = u1 * S + k;
  const double fu = (std::cos(au) * b0 - b1) / std::sin(au);
  const double cu = std::clamp(std::copysign(1.0, fu) / std::sqrt(fu * fu + b0 * b0), -1.0, 1.0);
  const double xu = std::clamp(-(cu * z0) / std::sqrt(std::max(1e-300, 1.0 - cu * cu)), x0, x1);
  const double dd = std::sqrt(xu * xu + z0 * z0);
  const double h0 = y0 / std::sqrt(dd * dd + y0 * y0), h1 = y1 / std::sqrt(dd * dd + y1 * y1);
  const double hv = h0 + u2 * (h1 - h0), hv2 = hv * hv;
  const double yv = hv2 < 1.0 - 1e-12 ? std::clamp(hv * dd / std::sqrt(1.0 - hv2), y0, y1) : y1;
  if (!(std::isfinite(xu) && std::isfinite(yv))) return false;  // degenerate: sample by area instead
  *q = o + f.ex * xu + f.ey * yv + z * z0;
  *solid_angle = S;
  return true;
}

}  // namespace

bool sample_rectangle_light(const RectangleLight& r, const Vec3& p, double u1, double u2, LightSample* out) {
  if (!(dot(p - r.center, r.normal) > 0.0)) return false;  // behind the emitting side, or in its plane
  const RectangleFrame f = rectangle_frame(r);
  Vec3 q;
  double solid_angle = 0.0;
  const bool by_solid_angle = sample_spherical_rectangle(f, p, u1, u2, &q, &solid_angle);
  if (!by_solid_angle) q = f.corner + f.ex * (u1 * f.w) + f.ey * (u2 * f.h);
  const Vec3 v = q - p;
  const double dist2 = v.length2();
  if (!(dist2 > 0.0)) return false;
  const double dist = std::sqrt(dist2);
  out->wi = v / dist;
  out->distance = dist;
  const double cos_l = -dot(out->wi, r.normal);  // the light's cosine at q towards p
  if (by_solid_angle) {
    out->weight = r.radiance * solid_angle;  // L / pdf, pdf = 1 / S
    return true;
  }
  if (cos_l <= 0.0) return false;
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
