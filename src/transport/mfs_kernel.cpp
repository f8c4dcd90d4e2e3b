// The MFS Green's function and the older small-angle beam forms (mfs_kernel.h).
#include "transport/mfs_kernel.h"

#include <fmt/format.h>

#include <cmath>

#include "core/math.h"
#include "nimbus/error.h"

namespace nimbus {

namespace {

// --- Functions of x = z / L, each finite and accurate from x = 0 to x = infinity -----------------
// x coth x  (-> 1 at 0, ~x for large x)
double x_coth(double x) {
  if (x < 1e-4) return 1.0 + x * x / 3.0;
  const double e = std::exp(-2.0 * x);
  return x * (1.0 + e) / (-std::expm1(-2.0 * x));
}
// x / sinh x  (-> 1 at 0, underflows to 0 without overflow for large x)
double x_csch(double x) {
  if (x < 1e-4) return 1.0 - x * x / 6.0;
  return 2.0 * x * std::exp(-x) / (-std::expm1(-2.0 * x));
}
// tanh(x) / x
double tanh_over_x(double x) { return x < 1e-4 ? 1.0 - x * x / 3.0 : std::tanh(x) / x; }
// 1 / cosh x
double sech(double x) { return 2.0 * std::exp(-x) / (1.0 + std::exp(-2.0 * x)); }

void check_finite_nonneg(double v, const char* name) {
  if (!std::isfinite(v) || v < 0.0)
    throw Error(fmt::format("mfs kernel: {} must be finite and >= 0 (got {})", name, v));
}

}  // namespace

// seed eq. 12, simplified: h = [x sinh x + 2 (1 - cosh x)] / sinh x = x - 2 tanh(x/2).
double mfs_h(double x) {
  if (std::abs(x) < 0.1) return x * x * x * mfs_h_over_x3(x);
  return x - 2.0 * std::tanh(0.5 * x);
}

double mfs_h_over_x3(double x) {
  const double x2 = x * x;
  // 2 tanh(x/2) = x - x^3/12 + x^5/120 - 17 x^7/20160 + 62 x^9/725760 - 2764 x^11/(155925 2^11) + ...
  if (std::abs(x) < 0.1) {
    const double x4 = x2 * x2;
    return 1.0 / 12.0 - x2 / 120.0 + 17.0 * x4 / 20160.0 - 62.0 * x4 * x2 / 725760.0 +
           2764.0 * x4 * x4 / (155925.0 * 2048.0);
  }
  return (x - 2.0 * std::tanh(0.5 * x)) / (x2 * x);
}

MfsScales mfs_scales(GaussianModel model, double z, double tau_s, double tau_a, double theta2) {
  if (!(z > 0.0) || !std::isfinite(z))
    throw Error(fmt::format("mfs kernel: path length z must be > 0 (got {})", z));
  check_finite_nonneg(tau_s, "tau_s");
  check_finite_nonneg(tau_a, "tau_a");
  if (!(theta2 > 0.0) || !std::isfinite(theta2))
    throw Error(fmt::format("mfs kernel: theta2 must be > 0 (got {})", theta2));
  MfsScales s;
  s.z = z;
  const double one_minus_ebz = -std::expm1(-tau_s);  // 1 - exp(-b z)
  s.W = std::exp(-tau_a) * one_minus_ebz;
  const double b = tau_s / z, a = tau_a / z;
  switch (model) {
    case GaussianModel::Dolin:
      s.T = theta2 * b;
      s.x = 0.0;
      break;
    case GaussianModel::Tes87:
      s.T = theta2 * b;  // [Tes87/88]: 1 / ell^2 = theta2 a b
      s.x = z * std::sqrt(a * s.T);
      break;
    case GaussianModel::Mfs:
      // notes: T = theta2 b / (1 - exp(-b z)) (the paper prints theta2^2); -> theta2 / z as b z -> 0.
      s.T = tau_s > 1e-300 ? theta2 * tau_s / (z * one_minus_ebz) : theta2 / z;
      s.x = z * std::sqrt(a * s.T);
      break;
  }
  return s;
}

// Corrected seed eq. 13 ("A" there, M in the notes), with T L = T z / x and every hyperbolic function
// divided by its x -> 0 behaviour:
//   M = x [(|g|^2 + |g'|^2) coth x - 2 g.g' csch x] / (2 T z) + |g + g'|^2 x tanh^2(x/2) / (2 T z h(x))
// Prefactor (notes; the paper's is 2 pi too large):
//   W / (4 pi^2 T^2 L^4 h(x) sinh x) = W / (4 pi^2 T^2 z^4) * (x / sinh x) / (h(x) / x^3)
double mfs_green(const MfsScales& s, const Vec2& gamma, const Vec2& gamma_prime) {
  if (!(s.T > 0.0)) return 0.0;
  const double x = s.x, tz = s.T * s.z;
  const double hx3 = mfs_h_over_x3(x);
  const double t2 = x < 1e-4 ? 0.5 : std::tanh(0.5 * x) / x;  // tanh(x/2) / x
  const double q = t2 * t2 / hx3;                             // x tanh^2(x/2) / h(x) (-> 3 at x = 0)
  const Vec2 sum = gamma + gamma_prime;
  const double M =
      ((gamma.length2() + gamma_prime.length2()) * x_coth(x) - 2.0 * gamma.dot(gamma_prime) * x_csch(x)) /
          (2.0 * tz) +
      sum.length2() * q / (2.0 * tz);
  const double pref = s.W / (4.0 * kPi * kPi * tz * tz * s.z * s.z) * x_csch(x) / hx3;
  return pref * std::exp(-M);
}

// Fixed axis.  The extremal path with gamma(0) = v0, gamma(z) = v and int gamma ds = r is
//   gamma = gamma_free + mu phi,  gamma_free = [v sinh(s/L) + v0 sinh((z - s)/L)] / sinh x,
//   phi(s) = 1 - cosh((s - z/2)/L) / cosh(x/2),  int phi = L h(x),  mu = (r - (v0 + v) L tanh(x/2)) / (L h).
// The cross term of the action vanishes (phi = 0 at both ends, gamma_free'' = gamma_free / L^2) and
// phi's own action is h / (2 T L), so
//   S = x [(|v0|^2 + |v|^2) coth x - 2 v0.v csch x] / (2 T z) + |r - (v0 + v) L tanh(x/2)|^2 / (2 T L^3 h).
// With r = 0 (axis through both ends) this is M above; the prefactor is the same.
double mfs_fixed_axis(const MfsScales& s, const Vec2& r, const Vec2& v, const Vec2& v0) {
  if (!(s.T > 0.0)) return 0.0;
  const double x = s.x, tz = s.T * s.z;
  const double hx3 = mfs_h_over_x3(x);
  const double l_tanh =
      x < 1e-4 ? 0.5 * s.z * (1.0 - x * x / 12.0) : s.z * std::tanh(0.5 * x) / x;  // L tanh(x/2)
  const Vec2 d = r - (v0 + v) * l_tanh;
  const double S = ((v0.length2() + v.length2()) * x_coth(x) - 2.0 * v0.dot(v) * x_csch(x)) / (2.0 * tz) +
                   d.length2() / (2.0 * tz * s.z * s.z * hx3);
  const double pref = s.W / (4.0 * kPi * kPi * tz * tz * s.z * s.z) * x_csch(x) / hx3;
  return pref * std::exp(-S);
}

GaussianBeam gaussian_beam(GaussianModel model, double z, double tau_s, double tau_a, double theta2) {
  const MfsScales s = mfs_scales(model, z, tau_s, tau_a, theta2);
  const double x = s.x, tz = s.T * s.z;
  GaussianBeam g;
  g.total = s.W * sech(x);
  g.var_angle = tz * tanh_over_x(x);                                                 // T L tanh x
  const double t2 = x < 1e-4 ? 0.5 * (1.0 - x * x / 12.0) : std::tanh(0.5 * x) / x;  // tanh(x/2) / x
  g.var_radius =
      tz * s.z * s.z * (mfs_h_over_x3(x) + t2 * t2 * tanh_over_x(x));  // T L^3 [h + tanh^2(x/2) tanh x]
  g.cov = s.z * t2 * g.var_angle;                                      // L tanh(x/2) T L tanh x
  return g;
}

// --- GaussianBeam marginals (2-D Gaussians in the small-angle plane) -----------------------------
double GaussianBeam::angular(double theta) const {
  if (!(var_angle > 0.0)) return 0.0;
  return total / (2.0 * kPi * var_angle) * std::exp(-theta * theta / (2.0 * var_angle));
}
double GaussianBeam::angular_within(double theta) const {
  if (!(var_angle > 0.0)) return total;
  return total * -std::expm1(-theta * theta / (2.0 * var_angle));
}
double GaussianBeam::radial(double r) const {
  if (!(var_radius > 0.0)) return 0.0;
  return total / (2.0 * kPi * var_radius) * std::exp(-r * r / (2.0 * var_radius));
}
double GaussianBeam::radial_within(double r) const {
  if (!(var_radius > 0.0)) return total;
  return total * -std::expm1(-r * r / (2.0 * var_radius));
}

}  // namespace nimbus
