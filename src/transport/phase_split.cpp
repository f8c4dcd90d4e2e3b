// The split of a phase function into a forward peak (clipped above the level at the cut angle) and
// a wide remainder, with tables of both lobes after peak scattering (PhaseSplit, phase_split.h).
#include "transport/phase_split.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "core/math.h"
#include "nimbus/error.h"
#include "transport/small_angle.h"

namespace nimbus {

namespace {

constexpr int kAngleNodes = 512;  // theta = pi u^2, u uniform: dense near the forward peak
constexpr int kTauNodes = 48;     // tau = kTauMax v^2, v uniform
constexpr int kMomentCap = 2000;

// Peak mass above the level P(theta_c) inside theta < theta_c (midpoint rule in theta).
double clipped_mass(const Phase& phase, double theta_c) {
  if (theta_c <= 0.0) return 0.0;
  const double level = phase_eval(phase, std::cos(theta_c));
  const int n = 4000;
  const double h = theta_c / n;
  double m = 0.0;
  for (int i = 0; i < n; ++i) {
    const double th = (i + 0.5) * h;
    m += std::max(0.0, phase_eval(phase, std::cos(th)) - level) * std::sin(th);
  }
  return 2.0 * kPi * h * m;
}

// The cut angle whose clipped mass is peak_fraction (clipped mass grows with theta_c for a
// forward-peaked P): bisection, or pi when the fraction is out of reach.
double cut_angle_for(const Phase& phase, double peak_fraction) {
  double lo = 0.0, hi = kPi;
  const double reachable = clipped_mass(phase, hi);
  if (peak_fraction >= reachable) return hi;
  for (int it = 0; it < 60; ++it) {
    const double mid = 0.5 * (lo + hi);
    (clipped_mass(phase, mid) < peak_fraction ? lo : hi) = mid;
  }
  return hi;
}

// Legendre moments of the wide part min(P, level) inside theta_c (tabulated finely, the cut angle a node).
std::vector<double> wide_part_moments(const Phase& phase, double theta_c, double level) {
  std::vector<double> theta, value;
  const int n = 4000;
  for (int i = 0; i < n; ++i) {
    const double u = double(i) / (n - 1), th = kPi * u * u;
    if (!theta.empty() && theta.back() < theta_c && th > theta_c) {
      theta.push_back(theta_c);
      value.push_back(level);
    }
    if (th == theta_c && !theta.empty() && theta.back() == th) continue;
    theta.push_back(th);
    value.push_back(th < theta_c ? std::min(phase_eval(phase, std::cos(th)), level)
                                 : phase_eval(phase, std::cos(th)));
  }
  return phase_legendre_moments(make_tabulated_phase("mfs-wide", theta, value), 1e-8, kMomentCap);
}

// The peak's moments by difference (or its Gaussian with the same <theta^2>); a delta without a peak.
std::vector<double> peak_part_moments(const std::vector<double>& chi_full,
                                      const std::vector<double>& chi_wide, double f, bool gaussian) {
  const size_t L = chi_full.size();
  std::vector<double> chi_peak(L, 1.0);  // no peak: a delta (tau_p stays 0 anyway)
  if (f > 0.0) {
    for (size_t l = 0; l < L; ++l) chi_peak[l] = (chi_full[l] - (1.0 - f) * chi_wide[l]) / f;
    if (gaussian) {
      const double theta2 = L > 2 ? (1.0 - chi_peak[2]) / 3.0 : 0.0;
      for (size_t l = 0; l < L; ++l) chi_peak[l] = std::exp(-0.5 * theta2 * double(l) * double(l + 1));
    }
  }
  return chi_peak;
}

// The series terms (2l+1)/(4 pi) chi_l P_l(mu) of the wide and the peak moments.
void legendre_terms(double mu, const std::vector<double>& chi_wide, const std::vector<double>& chi_peak,
                    std::vector<double>& cw, std::vector<double>& cp) {
  const size_t L = chi_wide.size();
  double p0 = 1.0, p1 = mu;
  for (size_t l = 0; l < L; ++l) {
    const double pl = l == 0 ? 1.0 : p1;
    const double c = (2.0 * l + 1.0) / (4.0 * kPi) * pl;
    cw[l] = c * chi_wide[l];
    cp[l] = c * chi_peak[l];
    if (l >= 1) {
      const double p2 = ((2.0 * l + 1.0) * mu * p1 - l * p0) / (l + 1.0);
      p0 = p1;
      p1 = p2;
    }
  }
}

// Tables [tau node][angle node] of the wide and peak lobes after optical depth tau_p of peak
// scattering: the unscattered term e^-tau P(mu) pointwise plus the scattered Legendre series.
template <typename Wide, typename Peak>
void tabulate_lobes(const std::vector<double>& chi_wide, const std::vector<double>& chi_peak, Wide&& wide,
                    Peak&& peak, std::vector<float>& wide_table, std::vector<float>& peak_table) {
  const size_t L = chi_wide.size();
  std::vector<double> tau(kTauNodes), e_tau(kTauNodes);
  std::vector<double> E(size_t(kTauNodes) * L);  // exp(-tau (1 - chi_peak_l)) - exp(-tau)
  for (int k = 0; k < kTauNodes; ++k) {
    const double v = double(k) / (kTauNodes - 1);
    tau[k] = PhaseSplit::kTauMax * v * v;
    e_tau[k] = std::exp(-tau[k]);
    for (size_t l = 0; l < L; ++l) E[k * L + l] = std::exp(-tau[k] * (1.0 - chi_peak[l])) - e_tau[k];
  }
  wide_table.assign(size_t(kTauNodes) * kAngleNodes, 0.0f);
  peak_table.assign(size_t(kTauNodes) * kAngleNodes, 0.0f);
  tbb::parallel_for(0, kAngleNodes, [&](int j) {
    const double u = double(j) / (kAngleNodes - 1), mu = std::cos(kPi * u * u);
    std::vector<double> cw(L), cp(L);
    legendre_terms(mu, chi_wide, chi_peak, cw, cp);
    const double w0 = wide(mu), q0 = peak(mu);
    for (int k = 0; k < kTauNodes; ++k) {
      double sw = 0.0, sp = 0.0;
      for (size_t l = 0; l < L; ++l) {
        sw += cw[l] * E[k * L + l];
        sp += cp[l] * E[k * L + l];
      }
      wide_table[size_t(k) * kAngleNodes + j] = float(std::max(0.0, e_tau[k] * w0 + sw));
      peak_table[size_t(k) * kAngleNodes + j] = float(std::max(0.0, e_tau[k] * q0 + sp));
    }
  });
}

}  // namespace

double auto_peak_fraction(const Phase& phase) {
  const double g = phase_mean_cosine(phase);
  return g > 0.0 ? g * g : 0.0;
}

PhaseSplit::PhaseSplit(const Phase& phase, double peak_fraction, bool gaussian) : phase_(phase) {
  if (!(peak_fraction >= 0.0 && peak_fraction <= 0.999))
    throw Error("phase split: peak fraction must be in [0, 0.999]");
  const std::vector<double> chi = phase_legendre_moments(phase, 1e-8, kMomentCap);

  // Cut angle for the requested fraction.
  level_ = std::numeric_limits<double>::infinity();
  if (peak_fraction > 1e-6) {
    theta_c_ = cut_angle_for(phase, peak_fraction);
    f_ = clipped_mass(phase, theta_c_);
    level_ = phase_eval(phase, std::cos(theta_c_));
  }

  // Moments of the wide part and of the peak by difference.
  chi_wide_ = f_ > 0.0 ? wide_part_moments(phase, theta_c_, level_) : chi;
  const size_t L = std::max(chi.size(), chi_wide_.size());
  std::vector<double> chi_full = chi;
  chi_full.resize(L, 0.0);
  chi_wide_.resize(L, 0.0);
  chi_peak_ = peak_part_moments(chi_full, chi_wide_, f_, gaussian);

  tabulate_lobes(
      chi_wide_, chi_peak_, [this](double mu) { return wide(mu); }, [this](double mu) { return peak(mu); },
      wide_table_, peak_table_);
}

double PhaseSplit::wide(double cos_theta) const {
  const double p = phase_eval(phase_, cos_theta);
  if (f_ <= 0.0) return p;
  const double th = std::acos(std::clamp(cos_theta, -1.0, 1.0));
  return (th < theta_c_ ? std::min(p, level_) : p) / (1.0 - f_);
}

double PhaseSplit::peak(double cos_theta) const {
  if (f_ <= 0.0) return 0.0;
  const double th = std::acos(std::clamp(cos_theta, -1.0, 1.0));
  if (th >= theta_c_) return 0.0;
  return std::max(0.0, phase_eval(phase_, cos_theta) - level_) / f_;
}

PhaseSplit::Angle PhaseSplit::angle(double cos_theta) {
  const double th = std::acos(std::clamp(cos_theta, -1.0, 1.0));
  const double a = std::sqrt(th / kPi) * (kAngleNodes - 1);
  const int j = std::min(int(a), kAngleNodes - 2);
  return {j, a - j};
}

double PhaseSplit::lookup(const std::vector<float>& table, double tau_p, const Angle& an) const {
  const double t = std::sqrt(std::clamp(tau_p, 0.0, kTauMax) / kTauMax) * (kTauNodes - 1);
  const int j = an.j, k = std::min(int(t), kTauNodes - 2);
  const double fa = an.fa, ft = t - k;
  const float* r0 = &table[size_t(k) * kAngleNodes + j];
  const float* r1 = r0 + kAngleNodes;
  return (1 - ft) * ((1 - fa) * r0[0] + fa * r0[1]) + ft * ((1 - fa) * r1[0] + fa * r1[1]);
}

}  // namespace nimbus
