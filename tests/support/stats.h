// Statistical helpers for tests: chi-square goodness of fit with a p-value, mean and standard error.
#pragma once

#include <cmath>
#include <functional>
#include <vector>

namespace nimbus::test {

// Upper regularised incomplete gamma Q(a, x) by series / continued fraction (Numerical Recipes'
// algorithm, written from the formulas): the chi-square survival function is Q(dof/2, chi2/2).
inline double gamma_q(double a, double x) {
  if (x <= 0.0) return 1.0;
  const double gln = std::lgamma(a);
  if (x < a + 1.0) {
    double ap = a, sum = 1.0 / a, del = sum;
    for (int n = 0; n < 10000; ++n) {
      ap += 1.0;
      del *= x / ap;
      sum += del;
      if (std::abs(del) < std::abs(sum) * 1e-15) break;
    }
    return 1.0 - sum * std::exp(-x + a * std::log(x) - gln);
  }
  double b = x + 1.0 - a, c = 1e300, d = 1.0 / b, h = d;
  for (int i = 1; i < 10000; ++i) {
    const double an = -i * (i - a);
    b += 2.0;
    d = an * d + b;
    if (std::abs(d) < 1e-300) d = 1e-300;
    c = b + an / c;
    if (std::abs(c) < 1e-300) c = 1e-300;
    d = 1.0 / d;
    const double del = d * c;
    h *= del;
    if (std::abs(del - 1.0) < 1e-15) break;
  }
  return std::exp(-x + a * std::log(x) - gln) * h;
}

struct ChiSquareResult {
  double chi2 = 0.0;
  int dof = 0;
  double p_value = 1.0;
};

// Pearson chi-square of observed counts against expected counts; cells with expected < min_expected
// are pooled together (the usual rule that keeps the statistic chi-square distributed).
inline ChiSquareResult chi_square(const std::vector<double>& observed, const std::vector<double>& expected,
                                  double min_expected = 5.0) {
  ChiSquareResult r;
  double pool_obs = 0.0, pool_exp = 0.0;
  int cells = 0;
  for (size_t i = 0; i < observed.size(); ++i) {
    if (expected[i] < min_expected) {
      pool_obs += observed[i];
      pool_exp += expected[i];
      continue;
    }
    r.chi2 += (observed[i] - expected[i]) * (observed[i] - expected[i]) / expected[i];
    ++cells;
  }
  if (pool_exp >= min_expected) {
    r.chi2 += (pool_obs - pool_exp) * (pool_obs - pool_exp) / pool_exp;
    ++cells;
  }
  r.dof = cells - 1;
  r.p_value = gamma_q(0.5 * r.dof, 0.5 * r.chi2);
  return r;
}

// Running mean and standard error of the mean.
struct MeanAccumulator {
  double n = 0.0, mean = 0.0, m2 = 0.0;
  void add(double x) {
    n += 1.0;
    const double d = x - mean;
    mean += d / n;
    m2 += d * (x - mean);
  }
  double variance() const { return n > 1.0 ? m2 / (n - 1.0) : 0.0; }
  double stderr_mean() const { return n > 1.0 ? std::sqrt(variance() / n) : 0.0; }
};

}  // namespace nimbus::test
