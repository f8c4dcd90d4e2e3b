#include "transport/small_angle.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "core/math.h"
#include "nimbus/error.h"

namespace nimbus {

namespace {

// Four-point Gauss-Legendre on [-1, 1].
constexpr double kGl4x[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563, 0.8611363115940526};
constexpr double kGl4w[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461, 0.3478548451374538};

// Moments by quadrature in theta: panels no wider than 1.5 / l_cap so P_l never turns more than 1.5 rad
// within one, nodes of a tabulated phase function kept as panel edges (its kinks).
std::vector<double> quadrature_moments(const Phase& phase, double theta_max, int l_cap, double tol) {
  std::vector<double> edges;
  if (const auto* t = std::get_if<TabulatedPhase>(&phase)) edges = t->theta;
  else edges = {0.0, theta_max};
  std::vector<double> mu, wf;  // nodes cos theta, weights * phase * sin * 2 pi
  const double hmax = 1.5 / l_cap;
  for (size_t i = 0; i + 1 < edges.size(); ++i) {
    const int m = std::max(1, int(std::ceil((edges[i + 1] - edges[i]) / hmax)));
    const double h = (edges[i + 1] - edges[i]) / m;
    for (int j = 0; j < m; ++j)
      for (int q = 0; q < 4; ++q) {
        const double th = edges[i] + h * (j + 0.5 + 0.5 * kGl4x[q]);
        mu.push_back(std::cos(th));
        wf.push_back(0.5 * h * kGl4w[q] * 2.0 * kPi * phase_eval(phase, std::cos(th)) * std::sin(th));
      }
  }
  std::vector<double> p0(mu.size(), 1.0), p1(mu), chi;
  double norm = 0.0;
  for (double w : wf) norm += w;
  chi.push_back(1.0);
  int small = 0;
  for (int l = 1; l <= l_cap; ++l) {
    double s = 0.0;
    for (size_t i = 0; i < mu.size(); ++i) s += wf[i] * p1[i];
    chi.push_back(s / norm);
    small = std::abs(chi.back()) < tol ? small + 1 : 0;
    if (small >= 8) break;
    for (size_t i = 0; i < mu.size(); ++i) {  // P_{l+1} = ((2l+1) mu P_l - l P_{l-1}) / (l+1)
      const double p2 = ((2 * l + 1) * mu[i] * p1[i] - l * p0[i]) / (l + 1);
      p0[i] = p1[i];
      p1[i] = p2;
    }
  }
  return chi;
}

std::vector<double> geometric_moments(double g, double w, double g2, double tol, int l_cap) {
  std::vector<double> chi{1.0};
  double a = 1.0, b = 1.0;
  int small = 0;
  for (int l = 1; l <= l_cap && small < 8; ++l) {
    a *= g;
    b *= g2;
    chi.push_back(w * a + (1.0 - w) * b);
    small = std::abs(chi.back()) < tol ? small + 1 : 0;
  }
  return chi;
}

// Legendre polynomials P_0..P_{n+1} at mu, into p.
void legendre_all(double mu, size_t n, std::vector<double>& p) {
  p.resize(n + 2);
  p[0] = 1.0;
  if (n + 2 > 1) p[1] = mu;
  for (size_t l = 1; l + 1 < p.size(); ++l) p[l + 1] = ((2 * l + 1) * mu * p[l] - l * p[l - 1]) / double(l + 1);
}

// int_0^1 mu P_l(mu) dmu for l = 0..n (from I_l = int_0^1 P_l = [P_{l-1}(0) - P_{l+1}(0)] / (2l+1)
// and mu P_l = [(l+1) P_{l+1} + l P_{l-1}] / (2l+1)).
std::vector<double> half_range_mu_moments(size_t n) {
  std::vector<double> p0;
  legendre_all(0.0, n + 2, p0);
  std::vector<double> I(n + 3, 0.0);
  I[0] = 1.0;
  for (size_t l = 1; l < I.size(); ++l) I[l] = (p0[l - 1] - p0[l + 1]) / double(2 * l + 1);
  std::vector<double> m(n + 1);
  for (size_t l = 0; l <= n; ++l) m[l] = ((l + 1) * I[l + 1] + (l > 0 ? l * I[l - 1] : 0.0)) / double(2 * l + 1);
  return m;
}

}  // namespace

std::vector<double> phase_legendre_moments(const Phase& phase, double tol, int l_cap) {
  if (const auto* p = std::get_if<HgPhase>(&phase)) return geometric_moments(p->g, 1.0, 0.0, tol, l_cap);
  if (const auto* p = std::get_if<DoubleHgPhase>(&phase)) return geometric_moments(p->g1, p->w, p->g2, tol, l_cap);
  if (std::holds_alternative<IsotropicPhase>(phase)) return {1.0};
  if (const auto* p = std::get_if<GaussPhase>(&phase)) {
    // chi_l ~ exp(-l (l+1) theta2 / 2): the moments end near l = sqrt(-2 ln(tol) / theta2).
    const int l_need = int(std::sqrt(-2.0 * std::log(tol) / p->theta2)) + 16;
    return quadrature_moments(phase, std::min(kPi, 40.0 * std::sqrt(p->theta2)), std::min(l_cap, l_need), tol);
  }
  return quadrature_moments(phase, kPi, l_cap, tol);
}

double phase_theta2(const Phase& phase) {
  if (const auto* p = std::get_if<GaussPhase>(&phase)) return p->theta2;
  const std::vector<double> chi = phase_legendre_moments(phase, 1e-12, 8);
  return (1.0 - (chi.size() > 2 ? chi[2] : 0.0)) / 3.0;  // <P_2> = chi_2, <cos^2> = (2 chi_2 + 1)/3
}

// --- ForwardPropagator ---------------------------------------------------------------------------
ForwardPropagator::ForwardPropagator(const Phase& phase) : chi_(phase_legendre_moments(phase)) {
  // Z(q) from Hilb's asymptotics P_l(cos theta) ~ J_0((l + 1/2) theta): Z(l + 1/2) = chi_l, linear in
  // between, Z = 1 on [0, 1/2], 0 beyond the last moment.  Cumulative integral at integer q.
  const size_t L = chi_.size();
  auto Z = [&](double q) {
    if (q <= 0.5) return 1.0;
    const double l = q - 0.5;
    const size_t i = size_t(l);
    if (i + 1 >= L) return i < L ? chi_[i] * (1.0 - (l - double(i))) : 0.0;
    return chi_[i] + (l - double(i)) * (chi_[i + 1] - chi_[i]);
  };
  auto c = std::make_shared<std::vector<double>>(L + 2, 0.0);
  for (size_t i = 1; i < c->size(); ++i) {
    // Z is piecewise linear with breaks at half-integers: integrate [i-1, i-1/2] and [i-1/2, i] exactly.
    const double a = double(i) - 1.0, m = a + 0.5, b = double(i);
    (*c)[i] = (*c)[i - 1] + 0.25 * (Z(a) + Z(m)) + 0.25 * (Z(m) + Z(b));
  }
  cumulative_z_ = c;
}

ForwardProfile ForwardPropagator::profile(double tau_s, double tau_a) const {
  if (!(tau_s >= 0.0) || !std::isfinite(tau_s) || !(tau_a >= 0.0) || !std::isfinite(tau_a))
    throw Error(fmt::format("forward propagator: optical depths must be finite and >= 0 (tau_s={}, tau_a={})", tau_s, tau_a));
  ForwardProfile p;
  p.tau_s_ = tau_s;
  p.tau_a_ = tau_a;
  p.cumulative_z_ = cumulative_z_;
  // f_l = exp(-tau_a) [exp(-tau_s (1 - chi_l)) - exp(-tau_s)] = exp(-tau_a - tau_s) expm1(tau_s chi_l)
  const double e = std::exp(-tau_a - tau_s);
  p.f_.resize(chi_.size());
  for (size_t l = 0; l < chi_.size(); ++l) p.f_[l] = e * std::expm1(tau_s * chi_[l]);
  // Trim the negligible tail.
  const double cut = 1e-14 * std::abs(p.f_[0]);
  while (p.f_.size() > 1 && std::abs(p.f_.back()) <= cut) p.f_.pop_back();
  p.total_ = p.f_[0];
  // Forward flux: int_{theta < pi/2} I(theta) cos theta dOmega = sum_l (2l+1)/2 f_l int_0^1 mu P_l dmu.
  const std::vector<double> m = half_range_mu_moments(p.f_.size());
  double ff = 0.0;
  for (size_t l = 0; l < p.f_.size(); ++l) ff += 0.5 * (2 * l + 1) * p.f_[l] * m[l];
  p.forward_flux_ = std::max(0.0, ff);
  return p;
}

// --- ForwardProfile ------------------------------------------------------------------------------
double ForwardProfile::angular(double theta) const {
  const double mu = std::cos(theta);
  double p0 = 1.0, p1 = mu, sum = 0.5 * f_[0] * 1.0;  // (2l+1)/(4 pi) with 2 pi pulled out below
  if (f_.size() > 1) sum += 1.5 * f_[1] * mu;
  for (size_t l = 1; l + 1 < f_.size(); ++l) {
    const double p2 = ((2 * l + 1) * mu * p1 - l * p0) / double(l + 1);
    p0 = p1;
    p1 = p2;
    sum += (l + 1.5) * f_[l + 1] * p1;
  }
  return sum / (2.0 * kPi);
}

double ForwardProfile::angular_within(double theta) const {
  // int_{cos theta}^1 P_l = [P_{l-1} - P_{l+1}] / (2l+1) (l >= 1), 1 - mu (l = 0).
  const double mu = std::cos(theta);
  std::vector<double> p;
  legendre_all(mu, f_.size(), p);
  double sum = 0.5 * f_[0] * (1.0 - mu);
  for (size_t l = 1; l < f_.size(); ++l) sum += 0.5 * f_[l] * (p[l - 1] - p[l + 1]);
  return sum;
}

double ForwardProfile::spectrum(double k) const {
  // Zbar(k) = C(k z) / (k z) in mean free paths (z = tau_s); C piecewise quadratic, linear interpolation
  // of the cumulative integral at integer q is accurate to the Z table's own resolution.
  const auto& c = *cumulative_z_;
  const double Q = k * tau_s_;
  double zbar = 1.0;
  if (Q > 1e-12) {
    const double qi = std::floor(Q);
    double C;
    if (qi + 1 >= double(c.size())) C = c.back();
    else {
      const size_t i = size_t(qi);
      C = c[i] + (Q - qi) * (c[i + 1] - c[i]);
    }
    zbar = C / Q;
  }
  return std::exp(-tau_a_ - tau_s_) * std::expm1(tau_s_ * zbar);
}

double ForwardProfile::radial_within(double r) const {
  if (!(r > 0.0) || !(total_ > 0.0)) return 0.0;
  // P(r) = int_0^inf R(k) r J1(k r) dk = int_0^inf R(x / r) J1(x) dx: Simpson on a log grid in x up to 1,
  // a uniform grid up to X, and the tail R ~ A / k = A r / x with int_X^inf J1(x)/x dx ~ J0(X)/X - J1(X)/X^2.
  auto f = [&](double x) { return spectrum(x / r) * std::cyl_bessel_j(1.0, x); };
  double sum = 0.0;
  {
    const int n = 240;
    const double u0 = std::log(1e-7), h = -u0 / n;  // x = e^u, u in [ln 1e-7, 0]
    for (int i = 0; i <= n; ++i) {
      const double x = std::exp(u0 + i * h);
      sum += (i == 0 || i == n ? 1.0 : (i % 2 ? 4.0 : 2.0)) * f(x) * x * h / 3.0;
    }
  }
  const double X = 600.0;
  {
    const int n = 12000;
    const double h = (X - 1.0) / n;
    for (int i = 0; i <= n; ++i)
      sum += (i == 0 || i == n ? 1.0 : (i % 2 ? 4.0 : 2.0)) * f(1.0 + i * h) * h / 3.0;
  }
  const double A = spectrum(X / r) * X / r;  // R(k) k at the cut
  sum += A * r * (std::cyl_bessel_j(0.0, X) / X - std::cyl_bessel_j(1.0, X) / (X * X));
  return sum;
}

double ForwardProfile::radial(double r) const {
  // Density per area = dP/dr / (2 pi r), by a centred difference of the cumulative power.
  const double h = std::max(1e-4 * r, 1e-9);
  const double lo = std::max(r - h, 0.0), hi = r + h;
  return (radial_within(hi) - radial_within(lo)) / (kPi * (hi * hi - lo * lo));
}

}  // namespace nimbus
