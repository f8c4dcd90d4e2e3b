// An affine placement: world = M * local, M a 3x4 matrix (the 4x4 matrix without its 0 0 0 1 row).
// Media (and, later, surfaces and lights) carry one, applied after their shape's own fields
// (docs/scene-format.md, "transform"). The inverse is computed once, at construction.
#pragma once

#include <array>

#include "nimbus/types.h"

namespace nimbus {

class Transform {
 public:
  using Matrix34 = std::array<std::array<double, 4>, 3>;  // row-major; column 3 is the translation

  Transform();  // identity

  // The affine map with the rows m[0..2] (world = m * [local, 1]). Throws nimbus::Error when m is not
  // finite or its 3x3 part is singular (see is_invertible); the scene parser checks first and names
  // the JSON field.
  static Transform from_matrix(const double m[3][4]);
  static Transform from_matrix(const Matrix34& m);
  // The three elementary maps of the scene's {"scale", "rotate", "translate"} form. rotation() is right
  // handed (counter-clockwise looking down `axis` towards the origin); `axis` need not be normalised
  // but must be non-zero. Multiples of 90 degrees have exact sines and cosines (0, +-1).
  static Transform scaling(const Vec3& s);
  static Transform rotation(const Vec3& axis, double degrees);
  static Transform translation(const Vec3& t);
  // Whether m is finite with a 3x3 part far from singular: |det| > 1e-12 times the product of its row
  // lengths (Hadamard's bound on |det|: the ratio is 1 for orthogonal rows, 0 for a singular matrix).
  static bool is_invertible(const Matrix34& m);

  Vec3 point(const Vec3& p) const;   // M p + t
  Vec3 vector(const Vec3& v) const;  // M v
  Vec3 normal(const Vec3& n) const;  // M^-T n (not normalised)

  Transform inverse() const;                    // world -> local
  Transform then(const Transform& next) const;  // next * this: this first, then next (never throws)
  bool is_identity() const { return identity_; }
  double determinant() const;  // of the 3x3 part
  const Matrix34& matrix() const { return m_; }
  const Matrix34& inverse_matrix() const { return inv_; }

 private:
  Transform(const Matrix34& m, const Matrix34& inv);

  Matrix34 m_, inv_;
  bool identity_ = true;  // exactly the identity (a fast path for callers)
};

}  // namespace nimbus
