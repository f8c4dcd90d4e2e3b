// The forward-peak / wide split of a phase function and the angular weights `mfs` needs (pure math).
//
// The phase function is split pointwise at a cut angle theta_c:
//     P = f P_peak + (1 - f) P_wide,
//     (1 - f) P_wide(theta) = min(P(theta), P(theta_c))  for theta < theta_c,  P(theta) beyond,
// so both parts are non-negative and normalised; the peak lives inside theta < theta_c.  f (the peak
// fraction) picks theta_c.  Peak scatters are carried by the small-angle propagator (they deflect light
// by little and are NOT extinction for the forward-carried light); wide scatters are discrete events
// (similarity / delta-M idea with a peak of finite width instead of a delta).
//
// After a path with peak optical depth tau_p (= f tau_s along it), light that left a scatter with the
// angular distribution Q has the distribution (Funk-Hecke: convolution multiplies Legendre moments)
//     Q_eff(tau_p, mu) = sum_l (2l + 1)/(4 pi) q_l exp(-tau_p (1 - chi_l^peak)) P_l(mu)
// (the generalised small-angle propagator of transport/small_angle.h for the peak, unscattered part
// included), whose integral over the sphere is 1 for every tau_p.  The tables hold Q_eff for
// Q = P_wide and Q = P_peak, the unscattered term exp(-tau_p) Q(mu) pointwise (no Gibbs ringing) plus
// the scattered series.
#pragma once

#include <vector>

#include "media/phase.h"

namespace nimbus {

// The "auto" peak fraction: f = min(chi_2, g) for mean cosine g > 0, 0 otherwise (at most 1; callers cap
// it). chi_2, the phase function's second Legendre moment, is the delta-Eddington fraction in general
// form (g^2 for HG, its special case): the part of the phase function whose removal leaves a wide part
// with little angular structure beyond l = 2, which the scatter grid's l <= 2 harmonics hold. For a
// double HG with a backward lobe, g^2 left much of the forward lobe in the wide part (the suite's
// 0.85 HG(0.9) + 0.15 HG(-0.4): f 0.50, wide chi_3 = 0.28, its l <= 2 expansion negative at 90 degrees);
// chi_2 takes it whole (f 0.705, wide chi_3 = 0.00). The cap at g keeps the wide part's mean cosine
// from turning negative where a backward lobe is as peaked as the forward one (chi_2 large, g small).
double auto_peak_fraction(const Phase& phase);
// f = g^2 for g > 0, else 0: the lidar model's rule (transport/lidar_model.h), validated with it. It has no
// grid of harmonics, and chi_2 made its double-HG ocean case worse (whole return -9.9 -> -15.5 % against
// photon Monte Carlo; docs/validation/lidar.md).
double g2_peak_fraction(const Phase& phase);

class PhaseSplit {
 public:
  // peak_fraction in [0, 0.999]: the part of the scattering carried forward by the propagator.
  // gaussian: replace the peak's moments by a Gaussian stand-in with the same theta2 (the closed form's
  // assumption) instead of its own (the generalised propagator).
  PhaseSplit(const Phase& phase, double peak_fraction, bool gaussian = false);

  double f() const { return f_; }                // achieved peak fraction
  double cut_angle() const { return theta_c_; }  // theta_c [rad]
  // Normalised parts, per sr, at cos_theta between propagation directions.
  double wide(double cos_theta) const;
  double peak(double cos_theta) const;
  // The probability that a scatter into cos_theta is a wide one, (1 - f) P_wide / P: 1 outside the cut
  // angle, min(1, P(theta_c) / P) inside (no acos, one phase evaluation inside only).
  double wide_share(double cos_theta) const {
    if (!(f_ > 0.0) || cos_theta <= cos_c_) return 1.0;
    const double p = phase_eval(phase_, cos_theta);
    return p > level_ ? level_ / p : 1.0;
  }
  // Propagated parts (see above), per sr; tau_p >= 0 (clamped to the table's range).
  double wide_eff(double tau_p, double cos_theta) const {
    return lookup(wide_table_, tau_p, angle(cos_theta));
  }
  double peak_eff(double tau_p, double cos_theta) const {
    return lookup(peak_table_, tau_p, angle(cos_theta));
  }
  // The same with the angle's place in the tables found once (an acos and a sqrt) for several lookups at
  // one cosine (every channel, both parts): the same values bit for bit.
  struct Angle {
    int j;      // the table's angle node below
    double fa;  // the fraction towards the next
  };
  static Angle angle(double cos_theta);
  double wide_eff(double tau_p, const Angle& a) const { return lookup(wide_table_, tau_p, a); }
  double peak_eff(double tau_p, const Angle& a) const { return lookup(peak_table_, tau_p, a); }

  const std::vector<double>& peak_moments() const { return chi_peak_; }
  // The peak's per-component mean square deflection, (1 - chi_2) / 3 (0 without a peak).
  double theta2() const {
    return f_ > 0.0 && chi_peak_.size() > 2 ? std::max(0.0, (1.0 - chi_peak_[2]) / 3.0) : 0.0;
  }
  const std::vector<double>& wide_moments() const { return chi_wide_; }

  static constexpr double kTauMax = 64.0;

 private:
  double lookup(const std::vector<float>& table, double tau_p, const Angle& a) const;

  Phase phase_;
  double f_ = 0.0, theta_c_ = 0.0, level_ = 0.0;  // level_ = P(theta_c)
  double cos_c_ = 1.0;                            // cos theta_c
  std::vector<double> chi_peak_, chi_wide_;
  std::vector<float> wide_table_, peak_table_;  // [tau node][angle node]
};

}  // namespace nimbus
