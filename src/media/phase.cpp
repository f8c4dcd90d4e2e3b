#include "media/phase.h"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cmath>

#include "core/rng.h"
#include "nimbus/error.h"

namespace nimbus {

double hg_eval(double cos_theta, double g) {
  const double denom = 1.0 + g * g - 2.0 * g * cos_theta;
  return kInv4Pi * (1.0 - g * g) / (denom * std::sqrt(denom));
}

double hg_sample_cos(double u, double g) {
  if (std::abs(g) < 1e-4) return 1.0 - 2.0 * u;
  const double s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u);
  return std::clamp((1.0 + g * g - s * s) / (2.0 * g), -1.0, 1.0);
}

double hg_theta2_one_minus_g(double g) { return 1.0 - g; }
double hg_theta2_one_minus_g2_over3(double g) { return (1.0 - g * g) / 3.0; }

namespace {

// Integral over [0, theta_max] of exp(-theta^2 / (2 t)) sin(theta) dtheta by composite Simpson.
double gauss_sphere_integral(double t) {
  const double theta_max = std::min(kPi, 40.0 * std::sqrt(t));
  const int n = 4096;
  const double h = theta_max / n;
  double sum = 0.0;
  for (int i = 0; i <= n; ++i) {
    const double th = i * h;
    const double f = std::exp(-th * th / (2.0 * t)) * std::sin(th);
    sum += f * ((i == 0 || i == n) ? 1.0 : (i % 2 ? 4.0 : 2.0));
  }
  return sum * h / 3.0;
}

// Integral of (a + b theta) sin(theta) over [t0, t1].
// int_t0^t1 (a + b t) sin t dt, without the cancellation of cos t1 - cos t0 at small angles (tables with a
// steep forward peak, e.g. Fournier-Forand's, have panels at 1e-7 rad): the cosine difference as a
// product of sines, and sin t - t cos t by its series below 0.1.
double linear_sin_integral(double a, double b, double t0, double t1) {
  const double cos_diff = 2.0 * std::sin(0.5 * (t1 + t0)) * std::sin(0.5 * (t1 - t0));  // cos t0 - cos t1
  auto G = [](double t) {                                                               // sin t - t cos t
    if (t >= 0.1) return std::sin(t) - t * std::cos(t);
    const double t2 = t * t;
    return t * t2 * (1.0 / 3.0 - t2 * (1.0 / 30.0 - t2 * (1.0 / 840.0 - t2 / 45360.0)));
  };
  return a * cos_diff + b * (G(t1) - G(t0));
}

double tabulated_eval_theta(const TabulatedPhase& p, double theta) {
  const auto it = std::upper_bound(p.theta.begin(), p.theta.end(), theta);
  const size_t i = std::clamp<size_t>(size_t(it - p.theta.begin()), 1, p.theta.size() - 1);
  const double t0 = p.theta[i - 1], t1 = p.theta[i];
  const double f = std::clamp((theta - t0) / (t1 - t0), 0.0, 1.0);
  return p.value[i - 1] + f * (p.value[i] - p.value[i - 1]);
}

double tabulated_sample_theta(const TabulatedPhase& p, double u) {
  const auto it = std::upper_bound(p.cdf.begin(), p.cdf.end(), u);
  const size_t i = std::clamp<size_t>(size_t(it - p.cdf.begin()), 1, p.cdf.size() - 1);
  const double t0 = p.theta[i - 1], t1 = p.theta[i];
  const double v0 = p.value[i - 1], v1 = p.value[i];
  const double b = (v1 - v0) / (t1 - t0), a = v0 - b * t0;
  const double target = (u - p.cdf[i - 1]) / (2.0 * kPi);
  // Invert the (monotone) partial integral on [t0, t1]: Newton steps, kept inside a shrinking
  // bracket (bisection where Newton would leave it).
  double lo = t0, hi = t1, t = 0.5 * (t0 + t1);
  for (int k = 0; k < 60; ++k) {
    const double f = linear_sin_integral(a, b, t0, t) - target;
    if (std::abs(f) <= 1e-15 * std::max(1.0, std::abs(target))) break;
    (f < 0.0 ? lo : hi) = t;
    const double slope = (a + b * t) * std::sin(t);
    const double next = slope > 0.0 ? t - f / slope : 0.5 * (lo + hi);
    t = (next > lo && next < hi) ? next : 0.5 * (lo + hi);
    if (hi - lo < 1e-14) break;
  }
  return t;
}

}  // namespace

GaussPhase make_gauss_phase(double theta2) {
  if (!(theta2 > 0.0) || !std::isfinite(theta2)) throw Error("gauss phase: theta2 must be > 0");
  GaussPhase p;
  p.theta2 = theta2;
  p.norm = 1.0 / (2.0 * kPi * gauss_sphere_integral(theta2));
  return p;
}

TabulatedPhase make_tabulated_phase(std::string name, std::vector<double> theta, std::vector<double> value) {
  if (theta.size() < 2 || theta.size() != value.size())
    throw Error(fmt::format("phase table '{}': needs matching theta and value columns of >= 2 rows", name));
  if (std::abs(theta.front()) > 1e-9 || std::abs(theta.back() - kPi) > 1e-6)
    throw Error(fmt::format("phase table '{}': theta must run from 0 to pi", name));
  for (size_t i = 0; i < theta.size(); ++i) {
    if (!std::isfinite(value[i]) || value[i] < 0.0)
      throw Error(fmt::format("phase table '{}': row {}: value must be finite and >= 0", name, i));
    if (i > 0 && !(theta[i] > theta[i - 1]))
      throw Error(fmt::format("phase table '{}': row {}: theta must increase", name, i));
  }
  TabulatedPhase p{std::move(name), std::move(theta), std::move(value), {}};
  p.cdf.assign(p.theta.size(), 0.0);
  for (size_t i = 1; i < p.theta.size(); ++i) {
    const double t0 = p.theta[i - 1], t1 = p.theta[i];
    const double b = (p.value[i] - p.value[i - 1]) / (t1 - t0), a = p.value[i - 1] - b * t0;
    p.cdf[i] = p.cdf[i - 1] + 2.0 * kPi * linear_sin_integral(a, b, t0, t1);
  }
  const double total = p.cdf.back();
  if (!(total > 0.0)) throw Error(fmt::format("phase table '{}': integrates to zero", p.name));
  for (double& v : p.value) v /= total;
  for (double& c : p.cdf) c /= total;
  return p;
}

double phase_eval(const Phase& phase, double cos_theta) {
  struct {
    double c;
    double operator()(const IsotropicPhase&) const { return kInv4Pi; }
    double operator()(const HgPhase& p) const { return hg_eval(c, p.g); }
    double operator()(const DoubleHgPhase& p) const {
      return p.w * hg_eval(c, p.g1) + (1.0 - p.w) * hg_eval(c, p.g2);
    }
    double operator()(const GaussPhase& p) const {
      const double th = std::acos(std::clamp(c, -1.0, 1.0));
      return p.norm * std::exp(-th * th / (2.0 * p.theta2));
    }
    double operator()(const TabulatedPhase& p) const {
      return tabulated_eval_theta(p, std::acos(std::clamp(c, -1.0, 1.0)));
    }
  } visitor{cos_theta};
  return std::visit(visitor, phase);
}

Vec3 phase_sample(const Phase& phase, const Vec3& wi, double u1, double u2) {
  struct {
    double u1, u2;
    double operator()(const IsotropicPhase&) const { return 1.0 - 2.0 * u1; }
    double operator()(const HgPhase& p) const { return hg_sample_cos(u1, p.g); }
    double operator()(const DoubleHgPhase& p) const {
      // Choose the lobe with u1, then reuse its rescaled remainder.
      if (u1 < p.w) return hg_sample_cos(u1 / p.w, p.g1);
      return hg_sample_cos((u1 - p.w) / (1.0 - p.w), p.g2);
    }
    double operator()(const GaussPhase& p) const {
      // Truncated 2-D Gaussian radius on [0, pi], accepted with probability sin(theta) / theta.
      // Retries draw from a stream hashed from (u1, u2), so the result stays a function of them.
      const double tail = 1.0 - std::exp(-kPi * kPi / (2.0 * p.theta2));
      Rng rng(std::bit_cast<uint64_t>(u1), std::bit_cast<uint64_t>(u2));
      double a = u1, b = u2;
      for (int k = 0; k < 10000; ++k) {
        const double th = std::sqrt(-2.0 * p.theta2 * std::log(1.0 - a * tail));
        const double accept = th > 0.0 ? std::sin(th) / th : 1.0;
        if (b < accept) return std::cos(th);
        a = rng.uniform();
        b = rng.uniform();
      }
      return 1.0;
    }
    double operator()(const TabulatedPhase& p) const { return std::cos(tabulated_sample_theta(p, u1)); }
  } visitor{u1, u2};
  const double cos_theta = std::visit(visitor, phase);
  // Azimuth: the Gaussian sampler consumed u2, so it takes phi from a stream hashed from (u1, u2).
  const bool used_u2 = std::holds_alternative<GaussPhase>(phase);
  const double u_phi =
      used_u2 ? Rng(std::bit_cast<uint64_t>(u2), std::bit_cast<uint64_t>(u1) ^ 0x5bd1e995u).uniform() : u2;
  return spherical_direction(cos_theta, 2.0 * kPi * u_phi, wi);
}

double phase_mean_cosine(const Phase& phase) {
  struct {
    double operator()(const IsotropicPhase&) const { return 0.0; }
    double operator()(const HgPhase& p) const { return p.g; }
    double operator()(const DoubleHgPhase& p) const { return p.w * p.g1 + (1.0 - p.w) * p.g2; }
    double operator()(const GaussPhase& p) const { return integrate(p); }
    double operator()(const TabulatedPhase& p) const {
      // Panel by panel (the table is linear in theta), 4-point Gauss-Legendre: exact to rounding for the
      // narrow panels of a forward peak, which a fixed grid in theta would miss.
      constexpr double x[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563,
                               0.8611363115940526};
      constexpr double w[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461,
                               0.3478548451374538};
      double sum = 0.0;
      for (size_t i = 1; i < p.theta.size(); ++i) {
        const double t0 = p.theta[i - 1], h = p.theta[i] - t0;
        for (int q = 0; q < 4; ++q) {
          const double f = 0.5 * (1.0 + x[q]), th = t0 + f * h;
          const double v = p.value[i - 1] + f * (p.value[i] - p.value[i - 1]);
          sum += 0.5 * h * w[q] * v * std::cos(th) * std::sin(th);
        }
      }
      return 2.0 * kPi * sum;
    }
    double integrate(const Phase& p) const {
      const int n = 20000;
      double sum = 0.0;
      for (int i = 0; i < n; ++i) {
        const double th = (i + 0.5) * kPi / n;
        sum += phase_eval(p, std::cos(th)) * std::cos(th) * std::sin(th);
      }
      return sum * 2.0 * kPi * kPi / n;
    }
  } visitor;
  return std::visit(visitor, phase);
}

std::string phase_describe(const Phase& phase) {
  struct {
    std::string operator()(const IsotropicPhase&) const { return "isotropic"; }
    std::string operator()(const HgPhase& p) const { return fmt::format("hg(g={})", p.g); }
    std::string operator()(const DoubleHgPhase& p) const {
      return fmt::format("double_hg(g1={}, g2={}, w={})", p.g1, p.g2, p.w);
    }
    std::string operator()(const GaussPhase& p) const { return fmt::format("gauss(theta2={})", p.theta2); }
    std::string operator()(const TabulatedPhase& p) const { return fmt::format("tabulated({})", p.name); }
  } visitor;
  return std::visit(visitor, phase);
}

}  // namespace nimbus
