// The generalised propagator's delay moments and its moment-matched gamma law (gsa_delay.h).
#include "transport/gsa_delay.h"

#include <fmt/format.h>

#include <cmath>
#include <limits>

#include "core/math.h"
#include "nimbus/error.h"

namespace nimbus {

DeflectionMoments deflection_moments(const Phase& phase) {
  if (const auto* g = std::get_if<GaussPhase>(&phase)) return {2.0 * g->theta2, 8.0 * g->theta2 * g->theta2};
  // 8-point Gauss-Legendre (Abramowitz & Stegun 25.4.30) on 600 panels growing geometrically from
  // 1e-7 rad to pi, and one panel on [0, 1e-7]: a Mie peak a few mrad wide gets tens of panels.
  static const double x[4] = {0.1834346424956498, 0.5255324099163290, 0.7966664774136267, 0.9602898564975363};
  static const double w[4] = {0.3626837833783620, 0.3137066458778873, 0.2223810344533745, 0.1012285362903763};
  const int panels = 600;
  const double t0 = 1e-7, ratio = std::pow(kPi / t0, 1.0 / panels);
  double norm = 0.0, s2 = 0.0, s4 = 0.0;
  auto panel = [&](double a, double b) {
    const double c = 0.5 * (a + b), h = 0.5 * (b - a);
    for (int j = 0; j < 4; ++j)
      for (double t : {c - h * x[j], c + h * x[j]}) {
        const double v = h * w[j] * 2.0 * kPi * phase_eval(phase, std::cos(t)) * std::sin(t), t2 = t * t;
        norm += v;
        s2 += v * t2;
        s4 += v * t2 * t2;
      }
  };
  panel(0.0, t0);
  double a = t0;
  for (int i = 0; i < panels; ++i) {
    const double b = i + 1 == panels ? kPi : a * ratio;
    panel(a, b);
    a = b;
  }
  return {s2 / norm, s4 / norm};
}

DelayMoments compound_poisson_delay_moments(double z, double b, const DeflectionMoments& m) {
  if (!(z > 0.0) || !(b > 0.0) || !(m.m2 > 0.0) || !(m.m4 > 0.0) || !std::isfinite(z + b + m.m2 + m.m4))
    throw Error("gsa delay: needs z > 0, b > 0 and positive finite deflection moments");
  const double p = -std::expm1(-b * z);  // probability of at least one scatter
  const double z2 = z * z;
  const double mean = m.m2 * b * z2 / 4.0;
  const double var = m.m4 * b * z2 * z / 12.0 + m.m2 * m.m2 * b * b * z2 * z2 / 24.0;
  const double second = var + mean * mean;
  return DelayMoments{mean / p, second / p - (mean / p) * (mean / p)};
}

GammaDelayLaw gsa_delay_law(double z, double b, double a, const DeflectionMoments& m) {
  if (!(a >= 0.0) || !std::isfinite(a)) throw Error("gsa delay: needs a >= 0");
  const DelayMoments d = compound_poisson_delay_moments(z, b, m);
  GammaDelayLaw g;
  g.shape = d.mean * d.mean / d.variance;
  const double scale0 = d.variance / d.mean;
  g.scale = scale0 / (1.0 + a * scale0);
  g.weight = std::exp(-a * z) * -std::expm1(-b * z) * std::pow(1.0 + a * scale0, -g.shape);
  return g;
}

double GammaDelayLaw::within(double lo, double hi) const {
  lo = std::max(lo, 0.0);
  if (!(hi > lo)) return 0.0;
  const double p_hi = std::isinf(hi) ? 1.0 : regularized_gamma_p(shape, hi / scale);
  return weight * (p_hi - regularized_gamma_p(shape, lo / scale));
}

double regularized_gamma_p(double k, double x) {
  if (!(k > 0.0) || !(x >= 0.0)) throw Error("regularized_gamma_p: needs k > 0, x >= 0");
  if (x == 0.0) return 0.0;
  if (std::isinf(x)) return 1.0;
  const double log_prefactor = -x + k * std::log(x) - std::lgamma(k);
  if (x < k + 1.0) {
    // gamma(k, x) = x^k e^-x sum_n x^n / (k (k + 1) ... (k + n))   (A&S 6.5.29)
    double term = 1.0 / k, sum = term;
    for (int n = 1; n < 1000 && term > 1e-17 * sum; ++n) {
      term *= x / (k + n);
      sum += term;
    }
    return std::min(1.0, sum * std::exp(log_prefactor));
  }
  // Q(k, x) = x^k e^-x / Gamma(k) * 1 / (x + 1 - k - 1 (1 - k) / (x + 3 - k - 2 (2 - k) / (x + 5 - k - ...)))
  // (A&S 6.5.31 as an even contraction), evaluated by the modified Lentz method.
  const double tiny = 1e-300;
  double bn = x + 1.0 - k, c = 1.0 / tiny, d = 1.0 / bn, h = d;
  for (int n = 1; n < 1000; ++n) {
    const double an = -n * (n - k);
    bn += 2.0;
    d = an * d + bn;
    if (std::abs(d) < tiny) d = tiny;
    c = bn + an / c;
    if (std::abs(c) < tiny) c = tiny;
    d = 1.0 / d;
    const double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1.0) < 1e-16) break;
  }
  return std::max(0.0, 1.0 - std::exp(log_prefactor) * h);
}

}  // namespace nimbus
