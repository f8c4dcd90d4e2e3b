// The Fournier-Forand phase function (fournier_forand.h).
#include "media/fournier_forand.h"

#include <fmt/format.h>

#include <cmath>
#include <limits>
#include <vector>

#include "core/math.h"
#include "media/phase.h"
#include "nimbus/error.h"

namespace nimbus {

namespace {

constexpr double kThetaMin = 1e-7, kThetaGeometric = 0.05;  // the table's nodes (make_ff_phase)

// h(x) = (delta^nu - 1 + nu x) / x^2 with x = 1 - delta: the binomial series sum_{k>=2} C(nu, k) (-x)^(k-2)
// for |x| < 0.01 (8 terms: relative error below 1e-14), else directly.
double ff_h(double x, double delta, double nu) {
  if (std::abs(x) < 0.01) {
    double c = -nu, sum = 0.0, xp = 1.0;  // c = C(nu, k) (-1)^k, from C(nu, 1) (-1) = -nu
    for (int k = 2; k <= 9; ++k) {
      c *= -(nu - k + 1) / k;
      sum += c * xp;
      xp *= x;
    }
    return sum;
  }
  return (std::expm1(nu * std::log(delta)) + nu * x) / (x * x);  // delta, not 1 - x: delta may be tiny
}

// P at s = sin^2(psi / 2) and cos psi (the header's form, its bracket divided by (1 - delta)^2 written
// as -nu / s + (1 - delta_180) h(1 - delta)).
double ff_eval_s(double s, double cos_psi, double n, double mu) {
  if (!(s > 0.0)) return std::numeric_limits<double>::infinity();
  const double nu = 0.5 * (3.0 - mu), K = 4.0 / (3.0 * (n - 1.0) * (n - 1.0)), delta = K * s;
  const double first =
      (-nu / s + (1.0 - K) * ff_h(1.0 - delta, delta, nu)) / (4.0 * kPi * std::pow(delta, nu));
  const double Knu = std::pow(K, nu);
  const double second = (1.0 - Knu) / (16.0 * kPi * (K - 1.0) * Knu) * (3.0 * cos_psi * cos_psi - 1.0);
  return first + second;
}

}  // namespace

bool ff_parameters_valid(double n, double mu) { return n > 1.0 && n <= 1.5 && mu > 3.0 && mu <= 5.0; }

double ff_eval(double cos_theta, double n, double mu) {
  const double c = std::clamp(cos_theta, -1.0, 1.0);
  return ff_eval_s(0.5 * (1.0 - c), c, n, mu);
}

double ff_eval_theta(double theta, double n, double mu) {
  const double sh = std::sin(0.5 * theta);
  return ff_eval_s(sh * sh, std::cos(theta), n, mu);
}

double ff_cdf(double theta, double n, double mu) {
  if (!(theta > 0.0)) return 0.0;
  if (theta >= kPi) return 1.0;
  // [1 - delta^(nu+1) - (1 - delta^nu) s] / ((1 - delta) delta^nu) = 1 + (1 - s) (delta^-nu - 1) / (1 - delta)
  const double nu = 0.5 * (3.0 - mu), K = 4.0 / (3.0 * (n - 1.0) * (n - 1.0));
  // = (delta^-nu (1 - s) - s (K - 1)) / (1 - delta), the form used below delta = 1/2 (no cancellation of
  // the leading 1 at small angles, where F ~ theta^(mu - 3) is tiny).
  const double sh = std::sin(0.5 * theta), s = sh * sh, delta = K * s, x = 1.0 - delta;
  double first = 0.0;
  if (delta < 0.5)
    first = (std::pow(delta, -nu) * (1.0 - s) - s * (K - 1.0)) / x;
  else
    first = 1.0 + (1.0 - s) * (x != 0.0 ? std::expm1(-nu * std::log(delta)) / x : nu);
  const double Knu = std::pow(K, nu), st = std::sin(theta);
  return first + (1.0 - Knu) / (8.0 * (K - 1.0) * Knu) * std::cos(theta) * st * st;
}

double ff_backscatter_fraction(double n, double mu) { return 1.0 - ff_cdf(0.5 * kPi, n, mu); }

double ff_mobley_n(double mu) { return 1.01 + 0.1542 * (mu - 3.0); }

double ff_mobley_mu(double b) {
  // B rises with mu along n(mu) (tested); bisection on (3, 5].
  auto B = [](double mu) { return ff_backscatter_fraction(ff_mobley_n(mu), mu); };
  double lo = 3.0 + 1e-6, hi = 5.0;
  const double b_lo = B(lo), b_hi = B(hi);
  const double b_min = std::min(b_lo, b_hi), b_max = std::max(b_lo, b_hi);
  if (!(b >= b_min && b <= b_max))
    throw Error(
        fmt::format("Fournier-Forand: backscatter fraction {} out of reach of Mobley et al.'s curve "
                    "n = 1.01 + 0.1542 (mu - 3), mu in (3, 5] ([{:.5g}, {:.5g}])",
                    b, b_min, b_max));
  const bool falling = b_hi < b_lo;
  for (int it = 0; it < 80; ++it) {
    const double mid = 0.5 * (lo + hi);
    ((B(mid) > b) == falling ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

TabulatedPhase make_ff_phase(double n, double mu) {
  if (!ff_parameters_valid(n, mu))
    throw Error(
        fmt::format("Fournier-Forand: needs n in (1, 1.5] and mu in (3, 5], got n = {}, mu = {}", n, mu));
  // Nodes: 0, then geometric (ratio 1.01) from 1e-7 to 0.05 rad, then steps of at most 0.0025 rad to pi;
  // values of the closed form (linear interpolation of the psi^(mu - 5) peak errs by < 1e-4 per panel).
  std::vector<double> theta{0.0};
  for (double t = kThetaMin; t < kThetaGeometric; t *= 1.01) theta.push_back(t);
  const int uniform = int(std::ceil((kPi - kThetaGeometric) / 0.0025));
  for (int i = 0; i <= uniform; ++i) theta.push_back(kThetaGeometric + (kPi - kThetaGeometric) * i / uniform);
  theta.back() = kPi;
  std::vector<double> value(theta.size());
  for (size_t i = 1; i < theta.size(); ++i) value[i] = ff_eval_theta(theta[i], n, mu);
  // The first panel: 2 pi int_0^t1 (v0 + (v1 - v0) t / t1) t dt = 2 pi t1^2 (v0 / 6 + v1 / 3) = F(t1).
  const double t1 = theta[1];
  value[0] = 6.0 * (ff_cdf(t1, n, mu) / (2.0 * kPi * t1 * t1) - value[1] / 3.0);
  for (size_t i = 0; i < theta.size(); ++i)
    if (!(value[i] >= 0.0) || !std::isfinite(value[i]))
      throw Error(
          fmt::format("Fournier-Forand: n = {}, mu = {} gives a negative or infinite value at "
                      "theta = {} rad",
                      n, mu, theta[i]));
  return make_tabulated_phase(fmt::format("ff(n={},mu={})", n, mu), std::move(theta), std::move(value));
}

}  // namespace nimbus
