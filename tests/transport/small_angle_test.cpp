// The generalised small-angle propagator: moments, the HG-Poisson identity, normalisation of the
// angular and radial profiles, and the spatial second moment against the random-walk value.
#include "transport/small_angle.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/math.h"
#include "nimbus/error.h"

namespace nimbus {
namespace {

TEST(SmallAngle, MomentsOfKnownPhaseFunctions) {
  const auto hg = phase_legendre_moments(HgPhase{0.9});
  for (size_t l = 0; l < 50; ++l) EXPECT_NEAR(hg[l], std::pow(0.9, double(l)), 1e-14);
  EXPECT_LT(hg.back(), 1e-11);
  const auto dhg = phase_legendre_moments(DoubleHgPhase{0.9, -0.3, 0.8});
  EXPECT_NEAR(dhg[3], 0.8 * 0.729 + 0.2 * -0.027, 1e-14);
  EXPECT_EQ(phase_legendre_moments(IsotropicPhase{}).size(), 1u);
  // Quadrature moments: chi_0 = 1, chi_1 = mean cosine (phase.cpp's independent quadrature),
  // and for a narrow Gaussian chi_l ~ exp(-l (l+1) theta2 / 2).
  const Phase gauss = make_gauss_phase(0.01);
  const auto g = phase_legendre_moments(gauss);
  EXPECT_NEAR(g[0], 1.0, 1e-12);
  EXPECT_NEAR(g[1], phase_mean_cosine(gauss), 1e-6);
  EXPECT_NEAR(g[10], std::exp(-55.0 * 0.01), 0.01);
  // A tabulated copy of HG(0.8) reproduces HG's moments to the table's accuracy.
  std::vector<double> th, v;
  for (int i = 0; i <= 4000; ++i) {
    const double t = kPi * std::pow(double(i) / 4000, 2.0);
    th.push_back(t);
    v.push_back(hg_eval(std::cos(t), 0.8));
  }
  const Phase tab = make_tabulated_phase("hg08", th, v);
  const auto tm = phase_legendre_moments(tab, 1e-9, 400);
  for (size_t l : {1, 2, 5, 20, 60}) EXPECT_NEAR(tm[l], std::pow(0.8, double(l)), 2e-4) << l;
  EXPECT_NEAR(phase_theta2(HgPhase{0.9}), (1 - 0.81) / 3.0, 1e-14);
  EXPECT_EQ(phase_theta2(make_gauss_phase(0.02)), 0.02);
}

TEST(SmallAngle, HgAngularProfileIsTheHgPoissonSeries) {
  const double g = 0.9, tau_s = 3.0, tau_a = 0.3;
  const ForwardProfile p = ForwardPropagator(HgPhase{g}).profile(tau_s, tau_a);
  for (double theta : {0.0, 0.01, 0.1, 0.5, 1.5, 3.0}) {
    double series = 0.0, pois = std::exp(-tau_s);
    for (int n = 1; n < 80; ++n) {
      pois *= tau_s / n;
      series += pois * hg_eval(std::cos(theta), std::pow(g, n));
    }
    series *= std::exp(-tau_a);
    EXPECT_NEAR(p.angular(theta), series, 1e-9 * series + 1e-13) << theta;
  }
}

TEST(SmallAngle, ProfilesAreNormalised) {
  for (const Phase& ph :
       {Phase{HgPhase{0.95}}, Phase{make_gauss_phase(0.01)}, Phase{DoubleHgPhase{0.9, -0.2, 0.9}}}) {
    const ForwardPropagator prop(ph);
    for (double tau_s : {0.1, 1.0, 10.0}) {
      const ForwardProfile p = prop.profile(tau_s, 0.05 * tau_s);
      const double total = std::exp(-0.05 * tau_s) * -std::expm1(-tau_s);
      EXPECT_NEAR(p.total(), total, 1e-12);
      EXPECT_NEAR(p.angular_within(kPi), total, 1e-10);
      // Midpoint quadrature of the point density agrees with the cumulative form.
      const int n = 20000;
      double sum = 0.0, flux = 0.0;
      for (int i = 0; i < n; ++i) {
        const double t = kPi * std::pow((i + 0.5) / n, 2.0), dt = 2.0 * kPi * (i + 0.5) / (double(n) * n);
        sum += p.angular(t) * 2.0 * kPi * std::sin(t) * dt;
        if (t < kPi / 2) flux += p.angular(t) * 2.0 * kPi * std::sin(t) * std::cos(t) * dt;
      }
      EXPECT_NEAR(sum, total, 1e-4 * total);
      EXPECT_NEAR(flux, p.forward_flux(), 1e-4 * total);
      EXPECT_NEAR(
          p.angular_within(0.3),
          [&] {
            double s = 0.0;
            for (int i = 0; i < n; ++i) {
              const double t = 0.3 * (i + 0.5) / n;
              s += p.angular(t) * 2.0 * kPi * std::sin(t) * 0.3 / n;
            }
            return s;
          }(),
          1e-4 * total);
      // The radial profile carries all scattered light.
      const double far = p.radial_within(1e4 * tau_s);
      EXPECT_NEAR(far, total, 2e-3 * total) << tau_s;
      double prev = 0.0;
      for (double r : {1e-3, 1e-2, 0.1, 1.0, 10.0}) {
        const double w = p.radial_within(r * tau_s);
        EXPECT_GE(w, prev - 5e-4 * total);  // the Hankel quadrature is good to ~1e-4 of the total
        prev = w;
      }
    }
  }
}

// For a Gaussian peak the n-scatter random walk gives <r^2> = 2 theta2 z^2 / 3 per scatter, so over
// all scattered light <r^2> = 2 theta2 b z^3 / (3 (1 - exp(-b z))).
TEST(SmallAngle, SpatialSecondMomentOfGaussianPeak) {
  const double th2 = 0.002;
  const ForwardPropagator prop(make_gauss_phase(th2));
  for (double z : {1.0, 5.0}) {
    const ForwardProfile p = prop.profile(z, 0.0);
    // <r^2> = int r^2 dP = int 2 r (total - P(r)) dr.
    const double sigma = std::sqrt(2.0 * th2 * z * z * z / 3.0);
    const int n = 300;
    const double rmax = 10.0 * sigma, h = rmax / n;
    double m2 = 0.0;
    for (int i = 0; i < n; ++i) {
      const double r = (i + 0.5) * h;
      m2 += 2.0 * r * (p.total() - p.radial_within(r)) * h;
    }
    m2 /= p.total();
    const double expected = 2.0 * th2 * z * z * z / (3.0 * -std::expm1(-z));
    EXPECT_NEAR(m2, expected, 0.03 * expected) << z;
  }
}

TEST(SmallAngle, RejectsBadDepths) {
  const ForwardPropagator prop(HgPhase{0.9});
  EXPECT_THROW(prop.profile(-1.0, 0.0), Error);
  EXPECT_THROW(prop.profile(1.0, std::nan("")), Error);
  EXPECT_NO_THROW(prop.profile(0.0, 0.0));
}

}  // namespace
}  // namespace nimbus
