// Fresnel reflectance and the refracted path through a flat surface (fresnel.h).
#include "transport/fresnel.h"

#include <algorithm>
#include <cmath>

namespace nimbus {

double fresnel_reflectance(double cos_i, double eta) {
  cos_i = std::clamp(cos_i, 0.0, 1.0);
  const double sin_t2 = (1.0 - cos_i * cos_i) / (eta * eta);
  if (sin_t2 >= 1.0) return 1.0;
  const double cos_t = std::sqrt(1.0 - sin_t2);
  const double rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
  const double rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
  return 0.5 * (rs * rs + rp * rp);
}

RefractedPath refracted_path(double h, double d, double rho, double n) {
  // n a / sqrt(a^2 + h^2) rises with a, (rho - a) / sqrt((rho - a)^2 + d^2) falls: bisection on [0, rho].
  double lo = 0.0, hi = rho;
  for (int it = 0; it < 200 && hi - lo > 1e-15 * (rho + h + d); ++it) {
    const double a = 0.5 * (lo + hi);
    const double lhs = n * a / std::hypot(a, h), rhs = (rho - a) / std::hypot(rho - a, d);
    (lhs < rhs ? lo : hi) = a;
  }
  RefractedPath p;
  p.a = 0.5 * (lo + hi);
  p.L_w = std::hypot(p.a, h);
  p.L_a = std::hypot(rho - p.a, d);
  p.cos_w = h / p.L_w;
  p.cos_a = d / p.L_a;
  p.spread = (h / p.cos_w + n * d / p.cos_a) *
             (h / (p.cos_w * p.cos_w) + n * d * p.cos_w / (p.cos_a * p.cos_a * p.cos_a));
  return p;
}

}  // namespace nimbus
