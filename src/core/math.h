// Small vector math on top of Imath (V3d is the position/direction type, Rgb the colour type).
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "nimbus/transform.h"
#include "nimbus/types.h"

namespace nimbus {

inline constexpr double kPi = std::numbers::pi;
inline constexpr double kInvPi = 1.0 / std::numbers::pi;
inline constexpr double kInv4Pi = 1.0 / (4.0 * std::numbers::pi);

inline double dot(const Vec3& a, const Vec3& b) { return a.dot(b); }
inline Vec3 cross(const Vec3& a, const Vec3& b) { return a.cross(b); }
inline double length(const Vec3& a) { return a.length(); }
inline Vec3 normalize(const Vec3& a) { return a / a.length(); }

inline double max_component(const Rgb& c) { return std::max({c.x, c.y, c.z}); }
inline double max_abs_component(const Vec3& v) {
  return std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)});
}
inline double min_component(const Rgb& c) { return std::min({c.x, c.y, c.z}); }
inline double average(const Rgb& c) { return (c.x + c.y + c.z) / 3.0; }
inline double luminance(const Rgb& c) { return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z; }
inline Rgb exp(const Rgb& c) { return {std::exp(c.x), std::exp(c.y), std::exp(c.z)}; }
// exp of each channel, taken once where neighbouring channels are equal (grey media, the common case), and
// not at all for a zero (exp(+-0) = 1 exactly: an empty step, a camera-side blur of l = 0): the same values
// bit for bit as exp(c), a third of the exps or none.
inline Rgb exp_channels(const Rgb& c) {
  Rgb r;
  r.x = c.x == 0.0 ? 1.0 : std::exp(c.x);
  r.y = c.y == c.x ? r.x : std::exp(c.y);
  r.z = c.z == c.y ? r.y : std::exp(c.z);
  return r;
}
inline bool is_finite(const Rgb& c) { return std::isfinite(c.x) && std::isfinite(c.y) && std::isfinite(c.z); }

// An orthonormal frame (s, t, n) around a unit vector n (Duff et al. 2017, branchless).
struct Frame {
  Vec3 s, t, n;
  explicit Frame(const Vec3& n_) : n(n_) {
    const double sign = std::copysign(1.0, n.z);
    const double a = -1.0 / (sign + n.z);
    const double b = n.x * n.y * a;
    s = Vec3(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
    t = Vec3(b, sign + n.y * n.y * a, -n.y);
  }
  Vec3 to_world(const Vec3& v) const { return s * v.x + t * v.y + n * v.z; }
  Vec3 to_local(const Vec3& v) const { return {dot(v, s), dot(v, t), dot(v, n)}; }
};

// Direction with polar cosine cos_theta around axis n and azimuth phi.
inline Vec3 spherical_direction(double cos_theta, double phi, const Vec3& n) {
  const double sin_theta = std::sqrt(std::max(0.0, 1.0 - cos_theta * cos_theta));
  return Frame(n).to_world({sin_theta * std::cos(phi), sin_theta * std::sin(phi), cos_theta});
}

// Cosine-weighted direction on the hemisphere around n (pdf cos(theta) / pi; Malley's method).
inline Vec3 cosine_direction(const Vec3& n, double u1, double u2) {
  return spherical_direction(std::sqrt(std::max(0.0, 1.0 - u1)), 2.0 * kPi * u2, n);
}

// Axis-aligned box.
struct Bounds {
  Vec3 lo{std::numeric_limits<double>::infinity()};
  Vec3 hi{-std::numeric_limits<double>::infinity()};
  bool empty() const { return !(lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z); }
  void extend(const Vec3& p) {
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  void extend(const Bounds& b) {
    if (!b.empty()) {
      extend(b.lo);
      extend(b.hi);
    }
  }
  bool overlaps(const Bounds& b) const {
    return lo.x <= b.hi.x && b.lo.x <= hi.x && lo.y <= b.hi.y && b.lo.y <= hi.y && lo.z <= b.hi.z &&
           b.lo.z <= hi.z;
  }
  bool contains(const Vec3& p) const {
    return p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y && p.z >= lo.z && p.z <= hi.z;
  }
  // Slab test: the parametric interval [t0, t1] of the ray inside the box, clipped to [tmin, tmax].
  bool intersect(const Vec3& o, const Vec3& d, double tmin, double tmax, double* t0, double* t1) const {
    for (int a = 0; a < 3; ++a) {
      const double inv = 1.0 / d[a];
      double tn = (lo[a] - o[a]) * inv, tf = (hi[a] - o[a]) * inv;
      if (tn > tf) std::swap(tn, tf);
      if (!(tn <= tf)) return false;  // NaN when o on the slab plane and d[a] == 0
      tmin = std::max(tmin, tn);
      tmax = std::min(tmax, tf);
      if (tmin > tmax) return false;
    }
    *t0 = tmin;
    *t1 = tmax;
    return true;
  }
};

// The corners of the box [lo, hi] through any map f, and the bounds of their images: for an affine f the
// image of the box is the parallelepiped these 8 points span, so the bounds are exact and conservative.
template <typename F>
Bounds bounds_of_mapped_box(const Vec3& lo, const Vec3& hi, F&& f) {
  Bounds b;
  for (int k = 0; k < 8; ++k)
    b.extend(f(Vec3(k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z)));
  return b;
}
// World bounds of a local box under a transform (empty stays empty).
inline Bounds transform_bounds(const Transform& t, const Bounds& b) {
  if (b.empty() || t.is_identity()) return b;
  return bounds_of_mapped_box(b.lo, b.hi, [&](const Vec3& p) { return t.point(p); });
}

}  // namespace nimbus
