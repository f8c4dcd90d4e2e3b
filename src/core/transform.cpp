// Affine transforms (include/nimbus/transform.h): the forward map and its inverse, computed once.
#include "nimbus/transform.h"

#include <fmt/format.h>

#include <cmath>

#include "core/math.h"
#include "nimbus/error.h"

namespace nimbus {

namespace {

using Matrix34 = Transform::Matrix34;

constexpr Matrix34 kIdentity{{{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}}};

double det3(const Matrix34& m) {
  return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
         m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
         m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

// The inverse affine map: A^-1 by the adjugate, translation -A^-1 t.
Matrix34 invert(const Matrix34& m) {
  const double inv_det = 1.0 / det3(m);
  Matrix34 r{};
  r[0][0] = (m[1][1] * m[2][2] - m[1][2] * m[2][1]) * inv_det;
  r[0][1] = (m[0][2] * m[2][1] - m[0][1] * m[2][2]) * inv_det;
  r[0][2] = (m[0][1] * m[1][2] - m[0][2] * m[1][1]) * inv_det;
  r[1][0] = (m[1][2] * m[2][0] - m[1][0] * m[2][2]) * inv_det;
  r[1][1] = (m[0][0] * m[2][2] - m[0][2] * m[2][0]) * inv_det;
  r[1][2] = (m[0][2] * m[1][0] - m[0][0] * m[1][2]) * inv_det;
  r[2][0] = (m[1][0] * m[2][1] - m[1][1] * m[2][0]) * inv_det;
  r[2][1] = (m[0][1] * m[2][0] - m[0][0] * m[2][1]) * inv_det;
  r[2][2] = (m[0][0] * m[1][1] - m[0][1] * m[1][0]) * inv_det;
  for (int i = 0; i < 3; ++i) r[i][3] = -(r[i][0] * m[0][3] + r[i][1] * m[1][3] + r[i][2] * m[2][3]);
  return r;
}

// a * b as 4x4 matrices with the row 0 0 0 1.
Matrix34 multiply(const Matrix34& a, const Matrix34& b) {
  Matrix34 r{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 4; ++j)
      r[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j] + (j == 3 ? a[i][3] : 0.0);
  return r;
}

// sin and cos of an angle in degrees, exact at multiples of 90 (a quarter turn maps voxels to voxels).
void sin_cos_degrees(double degrees, double* s, double* c) {
  const double turns = std::remainder(degrees, 360.0);  // in [-180, 180]
  if (turns == std::round(turns / 90.0) * 90.0) {
    const int q = (int(std::lround(turns / 90.0)) % 4 + 4) % 4;
    constexpr double kSin[4] = {0, 1, 0, -1}, kCos[4] = {1, 0, -1, 0};
    *s = kSin[q];
    *c = kCos[q];
    return;
  }
  const double rad = turns * (kPi / 180.0);
  *s = std::sin(rad);
  *c = std::cos(rad);
}

}  // namespace

Transform::Transform() : m_(kIdentity), inv_(kIdentity), identity_(true) {}

Transform::Transform(const Matrix34& m, const Matrix34& inv) : m_(m), inv_(inv), identity_(m == kIdentity) {}

bool Transform::is_invertible(const Matrix34& m) {
  for (const auto& row : m)
    for (double x : row)
      if (!std::isfinite(x)) return false;
  double bound = 1.0;
  for (int i = 0; i < 3; ++i) bound *= std::sqrt(m[i][0] * m[i][0] + m[i][1] * m[i][1] + m[i][2] * m[i][2]);
  const double det = det3(m);
  if (!(std::abs(det) > 1e-12 * bound) || !std::isfinite(bound)) return false;
  const Matrix34 inv = invert(m);
  for (const auto& row : inv)
    for (double x : row)
      if (!std::isfinite(x)) return false;
  return true;
}

Transform Transform::from_matrix(const Matrix34& m) {
  if (!is_invertible(m))
    throw Error(
        fmt::format("transform: the matrix must be finite and invertible (determinant {:g})", det3(m)));
  return Transform(m, m == kIdentity ? kIdentity : invert(m));
}

Transform Transform::from_matrix(const double m[3][4]) {
  Matrix34 a;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 4; ++j) a[i][j] = m[i][j];
  return from_matrix(a);
}

Transform Transform::scaling(const Vec3& s) {
  return from_matrix(Matrix34{{{s.x, 0, 0, 0}, {0, s.y, 0, 0}, {0, 0, s.z, 0}}});
}

Transform Transform::translation(const Vec3& t) {
  return from_matrix(Matrix34{{{1, 0, 0, t.x}, {0, 1, 0, t.y}, {0, 0, 1, t.z}}});
}

Transform Transform::rotation(const Vec3& axis, double degrees) {
  const double len = length(axis);
  if (!(len > 0.0) || !std::isfinite(len))
    throw Error("transform: rotation axis must be finite and non-zero");
  const Vec3 a = axis / len;
  double s, c;
  sin_cos_degrees(degrees, &s, &c);
  // Rodrigues: R = c I + s [a]x + (1 - c) a a^T.
  const double k = 1.0 - c;
  return from_matrix(Matrix34{{{c + k * a.x * a.x, k * a.x * a.y - s * a.z, k * a.x * a.z + s * a.y, 0},
                               {k * a.y * a.x + s * a.z, c + k * a.y * a.y, k * a.y * a.z - s * a.x, 0},
                               {k * a.z * a.x - s * a.y, k * a.z * a.y + s * a.x, c + k * a.z * a.z, 0}}});
}

Vec3 Transform::point(const Vec3& p) const {
  const Matrix34& m = m_;
  return {m[0][0] * p.x + m[0][1] * p.y + m[0][2] * p.z + m[0][3],
          m[1][0] * p.x + m[1][1] * p.y + m[1][2] * p.z + m[1][3],
          m[2][0] * p.x + m[2][1] * p.y + m[2][2] * p.z + m[2][3]};
}

Vec3 Transform::vector(const Vec3& v) const {
  const Matrix34& m = m_;
  return {m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z, m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
          m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z};
}

Vec3 Transform::normal(const Vec3& n) const {
  const Matrix34& r = inv_;  // (M^-1)^T n
  return {r[0][0] * n.x + r[1][0] * n.y + r[2][0] * n.z, r[0][1] * n.x + r[1][1] * n.y + r[2][1] * n.z,
          r[0][2] * n.x + r[1][2] * n.y + r[2][2] * n.z};
}

Transform Transform::inverse() const { return Transform(inv_, m_); }

Transform Transform::then(const Transform& next) const {
  if (identity_) return next;
  if (next.identity_) return *this;
  return Transform(multiply(next.m_, m_), multiply(inv_, next.inv_));
}

double Transform::determinant() const { return det3(m_); }

}  // namespace nimbus
