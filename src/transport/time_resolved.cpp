// Time bins and the closed forms of time-resolved transport (time_resolved.h).
#include "transport/time_resolved.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/math.h"
#include "nimbus/error.h"
#include "transport/phase_spec.h"

namespace nimbus {

std::vector<double> parse_time_edges(const std::string& what, const std::string& spec) {
  if (spec.empty()) throw Error(fmt::format("{}: empty list of time edges", what));
  std::vector<double> e;
  if (spec.find(':') != std::string::npos) {
    // lo:hi:N, N equal bins.
    std::string list = spec;
    for (char& ch : list)
      if (ch == ':') ch = ',';
    const std::vector<double> v = parse_number_list(what, list);
    if (v.size() != 3) throw Error(fmt::format("{}: '{}' is not of the form lo:hi:N", what, spec));
    const double n = v[2];
    if (!(n >= 1.0) || n != std::floor(n))
      throw Error(fmt::format("{}: N must be a whole number >= 1", what));
    if (n > double(kMaxTimeEdgeBins))
      throw Error(fmt::format("{}: {} bins is more than the {} allowed", what, n, kMaxTimeEdgeBins));
    for (size_t i = 0; i <= size_t(n); ++i) e.push_back(v[0] + (v[1] - v[0]) * double(i) / n);
  } else {
    e = parse_number_list(what, spec);
  }
  if (e.size() < 2) throw Error(fmt::format("{}: needs at least two edges (one bin)", what));
  if (e.size() - 1 > kMaxTimeEdgeBins)
    throw Error(fmt::format("{}: {} bins is more than the {} allowed", what, e.size() - 1, kMaxTimeEdgeBins));
  for (size_t i = 0; i < e.size(); ++i) {
    if (!(e[i] >= 0.0)) throw Error(fmt::format("{}: negative time {}", what, e[i]));
    if (i > 0 && !(e[i] > e[i - 1]))
      throw Error(fmt::format("{}: edges must increase ({} after {})", what, e[i], e[i - 1]));
  }
  return e;
}

double diffusion_reflectance_rate(double t, double mu_s_prime, double mu_a, double n, double A) {
  if (!(t > 0.0)) return 0.0;
  const double D = 1.0 / (3.0 * (mu_a + mu_s_prime));  // diffusion coefficient [length]
  const double v = 1.0 / n;                            // speed in the medium
  const double z0 = 1.0 / mu_s_prime;                  // depth of the equivalent isotropic source
  const double zp = z0 + 4.0 * A * D;  // z0 + 2 z_e, the image below the extrapolated boundary
  const double s = 4.0 * D * v * t;
  const double bracket = z0 * std::exp(-z0 * z0 / s) + zp * std::exp(-zp * zp / s);
  return 0.5 / std::sqrt(kPi * s) / t * std::exp(-mu_a * v * t) * bracket;
}

DelayMoments mfs_delay_moments(double z, double b, double a, double theta2) {
  if (!(z > 0.0) || !(b > 0.0) || !(a >= 0.0) || !(theta2 > 0.0) || !std::isfinite(z + b + a + theta2))
    throw Error("mfs delay: needs z > 0, b > 0, a >= 0, theta2 > 0, all finite");
  const double T = theta2 * b / -std::expm1(-b * z);  // the corrected kernel's angular diffusion rate
  const double x = z * std::sqrt(a * T);              // z / L
  // mean = T z^2/2 * tanh(x)/x; variance = T^2 z^4 * [x tanh x - x^2 sech^2 x] / (4 x^4), the latter
  // by its series below x = 0.05 (the bracket cancels to order x^4).
  const double x2 = x * x;
  const double mean_factor = x < 1e-4 ? 1.0 - x2 / 3.0 : std::tanh(x) / x;
  double var_factor;
  if (x < 0.05) {
    var_factor = 1.0 / 6.0 - 2.0 * x2 / 15.0 + 17.0 * x2 * x2 / 210.0;
  } else {
    const double sech = 1.0 / std::cosh(x);
    var_factor = (x * std::tanh(x) - x2 * sech * sech) / (4.0 * x2 * x2);
  }
  const double Tz2 = T * z * z;
  return DelayMoments{0.5 * Tz2 * mean_factor, Tz2 * Tz2 * var_factor};
}

DelayMoments poisson_delay_moments(double z, double b, double theta2) {
  if (!(z > 0.0) || !(b > 0.0) || !(theta2 > 0.0))
    throw Error("poisson delay: needs z > 0, b > 0, theta2 > 0");
  const double p = -std::expm1(-b * z);  // probability of at least one scatter
  const double z2 = z * z;
  const double mean = theta2 * b * z2 / 2.0;
  const double var = theta2 * theta2 * (2.0 * b * z2 * z / 3.0 + b * b * z2 * z2 / 6.0);
  const double second = var + mean * mean;
  return DelayMoments{mean / p, second / p - (mean / p) * (mean / p)};
}

namespace {

// f(u) of time_resolved.h: the density whose Laplace transform is 1 / cosh(sqrt(q)).
double sech_sqrt_density(double u) {
  if (!(u > 0.0)) return 0.0;
  double f = 0.0;
  if (u >= 0.25) {
    for (int k = 0; k < 40; ++k) {
      const double c = (k + 0.5) * kPi, term = (2 * k + 1) * std::exp(-c * c * u);
      f += (k % 2 ? -term : term);
      if (term < 1e-18) break;
    }
    return kPi * f;
  }
  for (int k = 0; k < 40; ++k) {
    const double m = 2 * k + 1, term = m * std::exp(-m * m / (4.0 * u));
    f += (k % 2 ? -term : term);
    if (term < 1e-300 || term < 1e-18 * std::abs(f)) break;
  }
  return f / std::sqrt(kPi * u * u * u);
}

}  // namespace

double mfs_delay_density(double tau, double z, double b, double a, double theta2) {
  if (!(z > 0.0) || !(b > 0.0) || !(a >= 0.0) || !(theta2 > 0.0))
    throw Error("mfs delay: needs z > 0, b > 0, a >= 0, theta2 > 0");
  if (!(tau > 0.0)) return 0.0;
  const double scale = theta2 * b / -std::expm1(-b * z) * z * z;  // T z^2
  const double W = std::exp(-a * z) * -std::expm1(-b * z);
  return W * std::exp(-a * tau) * sech_sqrt_density(tau / scale) / scale;
}

double mfs_delay_within(double lo, double hi, double z, double b, double a, double theta2) {
  // 8-point Gauss-Legendre nodes and weights on [-1, 1] (Abramowitz & Stegun 25.4.30), on pieces that
  // double in length from u = 2^-12 (the density is sharp near its peak at u ~ 0.1 and smooth beyond).
  static const double x[4] = {0.1834346424956498, 0.5255324099163290, 0.7966664774136267, 0.9602898564975363};
  static const double w[4] = {0.3626837833783620, 0.3137066458778873, 0.2223810344533745, 0.1012285362903763};
  const double scale = theta2 * b / -std::expm1(-b * z) * z * z;  // T z^2
  lo = std::max(lo, 0.0);
  hi = std::min(hi, 80.0 * scale);  // f(u) < 1e-80 beyond u = 80
  double sum = 0.0;
  auto piece = [&](double p0, double p1) {
    for (int i = 0; i < 4; ++i) {
      const double a0 = p0 + (p1 - p0) * i / 4, a1 = p0 + (p1 - p0) * (i + 1) / 4;
      const double c = 0.5 * (a0 + a1), h = 0.5 * (a1 - a0);
      for (int j = 0; j < 4; ++j)
        sum += h * w[j] *
               (mfs_delay_density(c - h * x[j], z, b, a, theta2) +
                mfs_delay_density(c + h * x[j], z, b, a, theta2));
    }
  };
  double p0 = lo;
  for (double u = std::ldexp(1.0, -12); u < 128.0 && p0 < hi; u *= 2.0)
    if (u * scale > p0) {
      const double p1 = std::min(u * scale, hi);
      piece(p0, p1);
      p0 = p1;
    }
  return sum;
}

}  // namespace nimbus
