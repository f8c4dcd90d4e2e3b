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

// Panel edges for integrals over [0, theta_c]: a tabulated phase function's nodes there (its kinks;
// a sharp table is dense near 0) and theta_c.
std::vector<double> clip_edges(const Phase& phase, double theta_c) {
  std::vector<double> edges{0.0};
  if (const auto* t = std::get_if<TabulatedPhase>(&phase))
    for (double th : t->theta)
      if (th > 0.0 && th < theta_c) edges.push_back(th);
  edges.push_back(theta_c);
  return edges;
}

// Peak mass above the level P(theta_c) inside theta < theta_c: four-point Gauss-Legendre on the
// panels of clip_edges, each cut into pieces no wider than theta_c / 500.
double clipped_mass(const Phase& phase, double theta_c) {
  if (theta_c <= 0.0) return 0.0;
  const double level = phase_eval(phase, std::cos(theta_c));
  std::vector<double> wf;
  sphere_quadrature([&](double th) { return std::max(0.0, phase_eval(phase, std::cos(th)) - level); },
                    clip_edges(phase, theta_c), theta_c / 500.0, nullptr, &wf);
  double m = 0.0;
  for (double w : wf) m += w;
  return m;
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

// The clipped-off peak max(0, P - level) inside theta < theta_c: its normalised Legendre moments by
// quadrature over [0, theta_c] only (a tabulated phase function's nodes there and theta_c as panel
// edges), its mass in *mass. The wide part's moments follow by difference from the whole function's.
std::vector<double> clipped_peak_moments(const Phase& phase, double theta_c, double level, double* mass) {
  return legendre_moments_of(
      [&](double th) { return std::max(0.0, phase_eval(phase, std::cos(th)) - level); },
      clip_edges(phase, theta_c), 1e-8, kMomentCap, mass);
}

// The peak's moments, or (gaussian) those of a Gaussian with the same <theta^2>.
std::vector<double> gaussian_stand_in(std::vector<double> chi_peak, bool gaussian) {
  if (gaussian) {
    const size_t L = chi_peak.size();
    const double theta2 = L > 2 ? (1.0 - chi_peak[2]) / 3.0 : 0.0;
    for (size_t l = 0; l < L; ++l) chi_peak[l] = std::exp(-0.5 * theta2 * double(l) * double(l + 1));
  }
  return chi_peak;
}

// The series terms (2l+1)/(4 pi) chi_l P_l(mu) of the wide and the peak moments, l < cw.size().
void legendre_terms(double mu, const std::vector<double>& chi_wide, const std::vector<double>& chi_peak,
                    std::vector<double>& cw, std::vector<double>& cp) {
  const size_t L = cw.size();
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

// The series' terms that matter: their first L, such that the terms from L on add less than kSeriesTail to any
// entry of the tables. Term l is (2l+1)/(4 pi) chi_l P_l(mu) E_l(tau), |P_l| <= 1, and the peak's scattered
// part E_l = exp(-tau (1 - chi_peak_l)) - exp(-tau) is at most |chi_peak_l| over tau where |chi_peak_l| < 1/2
// (|E_l| <= tau |chi| e^(-tau (1 - |chi|)) <= |chi| / (e (1 - |chi|))), else at most 1. The clipped peak's
// moments decay slowly (the peak has a kink at the cut angle: on HG 0.85, 3e-6 at l = 200, 1.5e-8 at l = 800,
// to the cap of 2000 moments), while both lobes' terms carry a factor chi_peak_l. HG 0.85 keeps 635 of its 1931
// terms (its tables took 27 ms single-threaded, ~6 % of the side-lit r = 10 sphere's CPU at 128 x 128), the
// double HG (0.9, -0.3, 0.8) 1851 of 2001. The tables match the whole series (PhaseSplit.TablesAreTheWholeSeries),
// and the suite's r = 1, r = 10, double HG, box and Disney cloud images were the same bit for bit.
constexpr double kSeriesTail = 1e-9;
size_t series_terms(const std::vector<double>& chi_wide, const std::vector<double>& chi_peak) {
  double tail = 0.0;
  for (size_t l = chi_wide.size(); l-- > 0;) {
    const double p = std::abs(chi_peak[l]), e = p < 0.5 ? p : 1.0;
    tail += (2.0 * double(l) + 1.0) / (4.0 * kPi) * (std::abs(chi_wide[l]) + p) * e;
    if (tail >= kSeriesTail) return l + 1;
  }
  return 0;
}

// Tables [tau node][angle node] of the wide and peak lobes after optical depth tau_p of peak
// scattering: the unscattered term e^-tau P(mu) pointwise plus the scattered Legendre series (its first
// series_terms terms). The series' sums run over l outermost, into one accumulator per tau node: each sum
// adds its terms in the order of l, as a dot product per node would, and the loop over the nodes vectorises.
template <typename Wide, typename Peak>
void tabulate_lobes(const std::vector<double>& chi_wide, const std::vector<double>& chi_peak, Wide&& wide,
                    Peak&& peak, std::vector<float>& wide_table, std::vector<float>& peak_table) {
  const size_t L = series_terms(chi_wide, chi_peak);
  std::vector<double> tau(kTauNodes), e_tau(kTauNodes);
  std::vector<double> E(L * kTauNodes);  // [l][tau node]: exp(-tau (1 - chi_peak_l)) - exp(-tau)
  for (int k = 0; k < kTauNodes; ++k) {
    const double v = double(k) / (kTauNodes - 1);
    tau[k] = PhaseSplit::kTauMax * v * v;
    e_tau[k] = std::exp(-tau[k]);
    for (size_t l = 0; l < L; ++l) E[l * kTauNodes + k] = std::exp(-tau[k] * (1.0 - chi_peak[l])) - e_tau[k];
  }
  wide_table.assign(size_t(kTauNodes) * kAngleNodes, 0.0f);
  peak_table.assign(size_t(kTauNodes) * kAngleNodes, 0.0f);
  tbb::parallel_for(0, kAngleNodes, [&](int j) {
    const double u = double(j) / (kAngleNodes - 1), mu = std::cos(kPi * u * u);
    std::vector<double> cw(L), cp(L);
    legendre_terms(mu, chi_wide, chi_peak, cw, cp);
    const double w0 = wide(mu), q0 = peak(mu);
    double sw[kTauNodes] = {}, sp[kTauNodes] = {};
    for (size_t l = 0; l < L; ++l) {
      const double* e = &E[l * kTauNodes];
      const double a = cw[l], b = cp[l];
      for (int k = 0; k < kTauNodes; ++k) {
        sw[k] += a * e[k];
        sp[k] += b * e[k];
      }
    }
    for (int k = 0; k < kTauNodes; ++k) {
      wide_table[size_t(k) * kAngleNodes + j] = float(std::max(0.0, e_tau[k] * w0 + sw[k]));
      peak_table[size_t(k) * kAngleNodes + j] = float(std::max(0.0, e_tau[k] * q0 + sp[k]));
    }
  });
}

}  // namespace

double auto_peak_fraction(const Phase& phase) {
  // HG: chi_2 = g^2 < g, the same number as ever.
  if (const auto* hg = std::get_if<HgPhase>(&phase)) return hg->g > 0.0 ? hg->g * hg->g : 0.0;
  const double g = phase_mean_cosine(phase);
  if (!(g > 0.0)) return 0.0;
  // A cap of 64, not 2: the quadrature follows the cap (at 2 a narrow Gauss peak's chi_2 is 0.006 low).
  const std::vector<double> chi = phase_legendre_moments(phase, 1e-8, 64);
  return std::clamp(std::min(chi.size() > 2 ? chi[2] : 0.0, g), 0.0, 1.0);
}

double g2_peak_fraction(const Phase& phase) {
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
    cos_c_ = std::cos(theta_c_);
  }

  // The peak's moments over its support, the wide part's by difference:
  // chi_wide = (chi - f chi_peak) / (1 - f).
  if (f_ > 0.0) {
    std::vector<double> chi_clip = clipped_peak_moments(phase, theta_c_, level_, &f_);
    const size_t L = std::max(chi.size(), chi_clip.size());
    chi_clip.resize(L, 0.0);
    chi_wide_.assign(L, 0.0);
    for (size_t l = 0; l < L; ++l)
      chi_wide_[l] = ((l < chi.size() ? chi[l] : 0.0) - f_ * chi_clip[l]) / (1.0 - f_);
    chi_peak_ = gaussian_stand_in(chi_clip, gaussian);
  } else {
    chi_wide_ = chi;
    chi_peak_.assign(chi.size(), 1.0);  // no peak: a delta (tau_p stays 0 anyway)
  }

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
