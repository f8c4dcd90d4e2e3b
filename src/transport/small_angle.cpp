// The generalised forward propagator and the phase functions' Legendre moments (small_angle.h).
#include "transport/small_angle.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/math.h"
#include "nimbus/error.h"

namespace nimbus {

namespace {

constexpr double kZStep = 0.25;    // spacing in q of the Z table
constexpr double kZDirect = 16.0;  // Z by direct Hankel quadrature below this q, by Hilb above

// Four-point Gauss-Legendre on [-1, 1].
constexpr double kGl4x[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563,
                             0.8611363115940526};
constexpr double kGl4w[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461, 0.3478548451374538};

// Moments by quadrature in theta of the phase function (its tabulated nodes as panel edges).
std::vector<double> quadrature_moments(const Phase& phase, double theta_max, int l_cap, double tol) {
  std::vector<double> edges;
  if (const auto* t = std::get_if<TabulatedPhase>(&phase))
    edges = t->theta;
  else
    edges = {0.0, theta_max};
  return legendre_moments_of([&](double th) { return phase_eval(phase, std::cos(th)); }, edges, tol, l_cap);
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
  for (size_t l = 1; l + 1 < p.size(); ++l)
    p[l + 1] = ((2 * l + 1) * mu * p[l] - l * p[l - 1]) / double(l + 1);
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
  for (size_t l = 0; l <= n; ++l)
    m[l] = ((l + 1) * I[l + 1] + (l > 0 ? l * I[l - 1] : 0.0)) / double(2 * l + 1);
  return m;
}

}  // namespace

void sphere_quadrature(const std::function<double(double)>& p, const std::vector<double>& edges, double hmax,
                       std::vector<double>* mu, std::vector<double>* wf) {
  if (mu) mu->clear();
  wf->clear();
  for (size_t i = 0; i + 1 < edges.size(); ++i) {
    const int m = std::max(1, int(std::ceil((edges[i + 1] - edges[i]) / hmax)));
    const double h = (edges[i + 1] - edges[i]) / m;
    for (int j = 0; j < m; ++j)
      for (int q = 0; q < 4; ++q) {
        const double th = edges[i] + h * (j + 0.5 + 0.5 * kGl4x[q]);
        if (mu) mu->push_back(std::cos(th));
        wf->push_back(0.5 * h * kGl4w[q] * 2.0 * kPi * p(th) * std::sin(th));
      }
  }
}

// Panels no wider than 1.5 / l_cap so that P_l never turns more than 1.5 rad within one.
std::vector<double> legendre_moments_of(const std::function<double(double)>& p,
                                        const std::vector<double>& edges, double tol, int l_cap,
                                        double* mass) {
  std::vector<double> mu, wf;  // nodes cos theta, weights * p * sin * 2 pi
  sphere_quadrature(p, edges, 1.5 / l_cap, &mu, &wf);
  std::vector<double> p0(mu.size(), 1.0), p1(mu), chi;
  double norm = 0.0;
  for (double w : wf) norm += w;
  if (mass) *mass = norm;
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

std::vector<double> phase_legendre_moments(const Phase& phase, double tol, int l_cap) {
  if (const auto* p = std::get_if<HgPhase>(&phase)) return geometric_moments(p->g, 1.0, 0.0, tol, l_cap);
  if (const auto* p = std::get_if<DoubleHgPhase>(&phase))
    return geometric_moments(p->g1, p->w, p->g2, tol, l_cap);
  if (std::holds_alternative<IsotropicPhase>(phase)) return {1.0};
  if (const auto* p = std::get_if<GaussPhase>(&phase)) {
    // chi_l ~ exp(-l (l+1) theta2 / 2): the moments end near l = sqrt(-2 ln(tol) / theta2).
    const int l_need = int(std::sqrt(-2.0 * std::log(tol) / p->theta2)) + 16;
    return quadrature_moments(phase, std::min(kPi, 40.0 * std::sqrt(p->theta2)), std::min(l_cap, l_need),
                              tol);
  }
  return quadrature_moments(phase, kPi, l_cap, tol);
}

double phase_theta2(const Phase& phase) {
  if (const auto* p = std::get_if<GaussPhase>(&phase)) return p->theta2;
  const std::vector<double> chi = phase_legendre_moments(phase, 1e-12, 8);
  return (1.0 - (chi.size() > 2 ? chi[2] : 0.0)) / 3.0;  // <P_2> = chi_2, <cos^2> = (2 chi_2 + 1)/3
}

// --- ForwardPropagator ---------------------------------------------------------------------------
namespace {

// Z(l + 1/2) = chi_l (Hilb's asymptotics P_l(cos theta) ~ J0((l + 1/2) theta)), Catmull-Rom in l,
// 0 beyond the last moment.
double z_hilb(const std::vector<double>& chi_l, double q) {
  const long L = long(chi_l.size());
  auto chi = [&](long l) {
    const long m = l < 0 ? -1 - l : l;
    return m < L ? chi_l[size_t(m)] : 0.0;
  };
  const double l = q - 0.5;
  const long i = long(std::floor(l));
  const double u = l - double(i);
  const double c0 = chi(i - 1), c1 = chi(i), c2 = chi(i + 1), c3 = chi(i + 2);
  return c1 +
         0.5 * u * (c2 - c0 + u * (2.0 * c0 - 5.0 * c1 + 4.0 * c2 - c3 + u * (3.0 * (c1 - c2) + c3 - c0)));
}

// Quadrature in theta of 2 pi P(theta) sin(theta) dtheta: geometric panels from 1e-6 to pi (and a
// tabulated phase function's nodes), 4-point Gauss-Legendre in each.
struct ThetaQuadrature {
  std::vector<double> nodes, weights;
  double norm = 0.0;  // the sum of the weights
};

ThetaQuadrature theta_quadrature(const Phase& phase) {
  std::vector<double> edges{0.0};
  for (double th = 1e-6; th < kPi; th *= 1.02) edges.push_back(th);
  if (const auto* tp = std::get_if<TabulatedPhase>(&phase))
    edges.insert(edges.end(), tp->theta.begin(), tp->theta.end());
  edges.push_back(kPi);
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  ThetaQuadrature quad;
  for (size_t i = 0; i + 1 < edges.size(); ++i) {
    const double h = edges[i + 1] - edges[i];
    for (int q = 0; q < 4; ++q) {
      const double th = edges[i] + h * (0.5 + 0.5 * kGl4x[q]);
      quad.nodes.push_back(th);
      quad.weights.push_back(0.5 * h * kGl4w[q] * 2.0 * kPi * phase_eval(phase, std::cos(th)) * std::sin(th));
    }
  }
  for (double w : quad.weights) quad.norm += w;
  return quad;
}

// Z(q) = 2 pi int_0^pi P(theta) J0(q theta) sin(theta) dtheta, normalised to Z(0) = 1.
double z_direct(const ThetaQuadrature& quad, double q) {
  double sum = 0.0;
  for (size_t i = 0; i < quad.nodes.size(); ++i)
    sum += quad.weights[i] * std::cyl_bessel_j(0.0, q * quad.nodes[i]);
  return sum / quad.norm;
}

}  // namespace

ForwardPropagator::ForwardPropagator(const Phase& phase) : chi_(phase_legendre_moments(phase)) {
  // Z(q), the small-angle (2-D) Fourier transform of the phase function:
  //  - for q <= kZDirect directly (z_direct): the transform of a non-negative function (so the spatial
  //    density stays non-negative), Z(0) = 1, and smooth at q = 0 because deflections are bounded by pi;
  //  - for large q from the moments by Hilb's asymptotics (z_hilb);
  //  - blended smoothly on [kZDirect / 2, kZDirect].
  const long L = long(chi_.size());
  const ThetaQuadrature quad = theta_quadrature(phase);
  auto Z = [&](double q) {
    if (q <= 0.5 * kZDirect) return z_direct(quad, q);
    if (q >= kZDirect) return z_hilb(chi_, q);
    const double u = (q - 0.5 * kZDirect) / (0.5 * kZDirect), w = u * u * (3.0 - 2.0 * u);  // smoothstep
    return (1.0 - w) * z_direct(quad, q) + w * z_hilb(chi_, q);
  };
  const size_t nq = size_t((L + 4) / kZStep) + 1;
  // Table: per node (Z, Z', C); cubic Hermite in between, C its exact integral, so R(k) is C^1 in k and
  // its Hankel transform free of ripples.
  const double eps = 1e-4;
  auto t = std::make_shared<std::vector<double>>(3 * nq, 0.0);
  for (size_t j = 0; j < nq; ++j) {
    const double q = double(j) * kZStep;
    const double z = Z(q), m = q == 0.0 ? 0.0 : (Z(q + eps) - Z(q - eps)) / (2.0 * eps);
    (*t)[3 * j] = z;
    (*t)[3 * j + 1] = m;
    if (j > 0) {
      const double z0 = (*t)[3 * j - 3], m0 = (*t)[3 * j - 2];
      (*t)[3 * j + 2] = (*t)[3 * j - 1] + kZStep * (0.5 * (z0 + z) + kZStep * (m0 - m) / 12.0);
    }
  }
  cumulative_z_ = t;
}

ForwardProfile ForwardPropagator::profile(double tau_s, double tau_a) const {
  if (!(tau_s >= 0.0) || !std::isfinite(tau_s) || !(tau_a >= 0.0) || !std::isfinite(tau_a))
    throw Error(fmt::format("forward propagator: optical depths must be finite and >= 0 (tau_s={}, tau_a={})",
                            tau_s, tau_a));
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

double ForwardProfile::zbar_and_z(double k, double* z_at) const {
  // Zbar(k) = C(Q) / Q with Q = k z (mean free paths, z = tau_s), C(Q) = int_0^Q Z, from the Hermite table.
  const auto& t = *cumulative_z_;
  const size_t nq = t.size() / 3;
  const double Q = k * tau_s_;
  if (!(Q > 1e-12)) {
    *z_at = 1.0;
    return 1.0;
  }
  const double qi = std::floor(Q / kZStep);
  if (qi + 1 >= double(nq)) {
    *z_at = 0.0;
    return t[3 * (nq - 1) + 2] / Q;
  }
  const size_t i = size_t(qi);
  const double u = Q / kZStep - qi, h = kZStep;
  const double z0 = t[3 * i], m0 = t[3 * i + 1], c0 = t[3 * i + 2], z1 = t[3 * i + 3], m1 = t[3 * i + 4];
  const double u2 = u * u, u3 = u2 * u, u4 = u3 * u;
  *z_at =
      (2 * u3 - 3 * u2 + 1) * z0 + (u3 - 2 * u2 + u) * h * m0 + (-2 * u3 + 3 * u2) * z1 + (u3 - u2) * h * m1;
  const double C = c0 + h * ((u - u3 + 0.5 * u4) * z0 + (0.5 * u2 - 2.0 * u3 / 3.0 + 0.25 * u4) * h * m0 +
                             (u3 - 0.5 * u4) * z1 + (0.25 * u4 - u3 / 3.0) * h * m1);
  return C / Q;
}

double ForwardProfile::spectrum(double k) const {
  double z_at = 0.0;
  const double zbar = zbar_and_z(k, &z_at);
  return std::exp(-tau_a_ - tau_s_) * std::expm1(tau_s_ * zbar);
}

double ForwardProfile::spectrum_slope(double k) const {
  // d/dk exp(-c z) expm1(tau_s Zbar) = exp(-c z) exp(tau_s Zbar) tau_s (Z(kz) - Zbar(k)) / k
  double z_at = 0.0;
  const double zbar = zbar_and_z(k, &z_at);
  if (!(k > 0.0)) return 0.0;
  return std::exp(-tau_a_ - tau_s_ + tau_s_ * zbar) * tau_s_ * (z_at - zbar) / k;
}

double ForwardProfile::radial_within(double r) const {
  if (!(r > 0.0) || !(total_ > 0.0)) return 0.0;
  // P(r) = int_0^inf R(k) r J1(k r) dk = int_0^inf R(x / r) J1(x) dx.  Simpson on a log grid below x = 1
  // and a uniform one (step 0.1) up to X = 200.  Two tails:
  //  - when k = X / r is beyond the tabulated Z, R(k) ~ A / k exactly (A = exp(-c z) C(inf)), and
  //    int_X^inf (A r / x) J1(x) dx ~ A r [J0(X)/X + J1(X)/X^2];
  //  - otherwise (large r) integrate by parts instead: P = R(0) + int_0^inf J0(x) R'(x / r) / r dx, whose
  //    tail -J1(X) R'(X/r) / r is small, and which has no cancellation problem when P ~ total.
  const double X = 200.0;
  const size_t nq = cumulative_z_->size() / 3;
  const bool asymptotic = X / r * tau_s_ > double(nq) * kZStep && spectrum(X / r) < 1e-3 * total_;
  auto f = [&](double x) {
    return asymptotic ? spectrum(x / r) * std::cyl_bessel_j(1.0, x)
                      : std::cyl_bessel_j(0.0, x) * spectrum_slope(x / r) / r;
  };
  double sum = 0.0;
  {
    const int n = 160;
    const double u0 = std::log(1e-8), h = -u0 / n;  // x = e^u, u in [ln 1e-8, 0]
    for (int i = 0; i <= n; ++i) {
      const double x = std::exp(u0 + i * h);
      sum += (i == 0 || i == n ? 1.0 : (i % 2 ? 4.0 : 2.0)) * f(x) * x * h / 3.0;
    }
  }
  {
    const int n = 2000;
    const double h = (X - 1.0) / n;
    for (int i = 0; i <= n; ++i)
      sum += (i == 0 || i == n ? 1.0 : (i % 2 ? 4.0 : 2.0)) * f(1.0 + i * h) * h / 3.0;
  }
  if (asymptotic) {
    const double A = spectrum(X / r) * X / r;
    sum += A * r * (std::cyl_bessel_j(0.0, X) / X + std::cyl_bessel_j(1.0, X) / (X * X));
  } else {
    sum = total_ + sum - std::cyl_bessel_j(1.0, X) * spectrum_slope(X / r) / r;
  }
  return std::clamp(sum, 0.0, total_);
}

double ForwardProfile::radial(double r) const {
  // Density per area = dP/dr / (2 pi r), by a centred difference of the cumulative power.
  const double h = std::max(1e-4 * r, 1e-9);
  const double lo = std::max(r - h, 0.0), hi = r + h;
  return (radial_within(hi) - radial_within(lo)) / (kPi * (hi * hi - lo * lo));
}

}  // namespace nimbus
