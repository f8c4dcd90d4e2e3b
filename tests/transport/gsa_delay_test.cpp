// The generalised propagator's delay (gsa_delay.h): the incomplete gamma function against closed forms,
// the compound-Poisson delay moments against a direct simulation of the small-angle process with a
// non-Gaussian deflection law, the deflection moments against sampling the phase functions, and the
// moment-matched gamma law's weight, moments and absorption tilt.
#include "transport/gsa_delay.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "core/math.h"
#include "core/rng.h"
#include "media/phase.h"
#include "transport/time_resolved.h"

namespace nimbus {
namespace {

TEST(GsaDelay, IncompleteGammaMatchesClosedForms) {
  for (double x : {1e-6, 0.01, 0.3, 0.9, 1.5, 2.0, 4.0, 10.0, 40.0}) {
    EXPECT_NEAR(regularized_gamma_p(1.0, x), -std::expm1(-x), 1e-13) << x;
    EXPECT_NEAR(regularized_gamma_p(0.5, x), std::erf(std::sqrt(x)), 1e-13) << x;
    EXPECT_NEAR(regularized_gamma_p(2.0, x), 1.0 - std::exp(-x) * (1.0 + x), 1e-13) << x;
    EXPECT_NEAR(regularized_gamma_p(3.0, x), 1.0 - std::exp(-x) * (1.0 + x + x * x / 2.0), 1e-13) << x;
  }
  EXPECT_EQ(regularized_gamma_p(0.2, 0.0), 0.0);
  EXPECT_EQ(regularized_gamma_p(0.2, std::numeric_limits<double>::infinity()), 1.0);
}

TEST(GsaDelay, GaussianDeflectionsGiveThePoissonMoments) {
  const double theta2 = 0.004;
  const DeflectionMoments m = deflection_moments(make_gauss_phase(theta2));
  EXPECT_DOUBLE_EQ(m.m2, 2.0 * theta2);
  EXPECT_DOUBLE_EQ(m.m4, 8.0 * theta2 * theta2);
  for (double z : {0.1, 1.0, 3.0}) {
    const DelayMoments got = compound_poisson_delay_moments(z, 1.3, m);
    const DelayMoments want = poisson_delay_moments(z, 1.3, theta2);
    EXPECT_NEAR(got.mean, want.mean, 1e-12 * want.mean);
    EXPECT_NEAR(got.variance, want.variance, 1e-12 * want.variance);
  }
}

std::pair<double, double> mean_and_error(const std::vector<double>& v) {
  double m = 0.0, q = 0.0;
  for (double x : v) m += x / double(v.size());
  for (double x : v) q += (x - m) * (x - m);
  return {m, std::sqrt(q / double(v.size() - 1) / double(v.size()))};
}

TEST(GsaDelay, MomentsMatchADirectSimulationWithExponentialDeflections) {
  // |theta| exponential with mean c (m2 = 2 c^2, m4 = 24 c^4: a kurtosis three times the Gaussian's),
  // uniform azimuth, at Poisson(b) times on [0, z]; tau = 1/2 int |gamma|^2, conditioned on a scatter.
  const double z = 2.0, b = 1.5, c = 1.0;
  const DeflectionMoments m{2.0 * c * c, 24.0 * c * c * c * c};
  const int batches = 20, per = 20000;
  std::vector<double> means, vars;
  for (int bt = 0; bt < batches; ++bt) {
    double s1 = 0.0, s2 = 0.0, n = 0.0;
    for (int i = 0; i < per; ++i) {
      Rng rng(17, uint64_t(bt) * per + i);
      double t = 0.0, gx = 0.0, gy = 0.0, tau = 0.0;
      bool scattered = false;
      while (true) {
        const double step = -std::log(1.0 - rng.uniform()) / b;
        const double seg = std::min(step, z - t);
        tau += 0.5 * (gx * gx + gy * gy) * seg;
        if (t + step >= z) break;
        t += step;
        const double r = -c * std::log(1.0 - rng.uniform()), phi = 2.0 * kPi * rng.uniform();
        gx += r * std::cos(phi);
        gy += r * std::sin(phi);
        scattered = true;
      }
      if (!scattered) continue;
      s1 += tau;
      s2 += tau * tau;
      n += 1.0;
    }
    means.push_back(s1 / n);
    vars.push_back(s2 / n - (s1 / n) * (s1 / n));
  }
  const auto [mean, em] = mean_and_error(means);
  const auto [var, ev] = mean_and_error(vars);
  const DelayMoments exact = compound_poisson_delay_moments(z, b, m);
  EXPECT_NEAR(mean, exact.mean, 5.0 * em);
  EXPECT_NEAR(var, exact.variance, 5.0 * ev);
  EXPECT_LT(ev, 0.03 * exact.variance);  // power
  // The Gaussian law with the same m2 (m4 = 2 m2^2) is far off: the m4 term is seen.
  const DelayMoments gauss = compound_poisson_delay_moments(z, b, {m.m2, 2.0 * m.m2 * m.m2});
  EXPECT_GT(std::abs(var - gauss.variance), 10.0 * ev);
}

TEST(GsaDelay, DeflectionMomentsMatchSamplingThePhaseFunction) {
  const std::vector<Phase> phases{
      HgPhase{0.9}, HgPhase{0.95}, DoubleHgPhase{0.95, -0.3, 0.9},
      make_tabulated_phase("t", {0.0, 0.02, 0.1, 0.5, 1.5, kPi}, {400.0, 200.0, 20.0, 1.0, 0.2, 0.3})};
  for (const Phase& p : phases) {
    const DeflectionMoments q = deflection_moments(p);
    std::vector<double> m2s, m4s;
    for (int bt = 0; bt < 20; ++bt) {
      double s2 = 0.0, s4 = 0.0;
      const int per = 10000;
      for (int i = 0; i < per; ++i) {
        Rng rng(5, uint64_t(bt) * per + i);
        const double u1 = rng.uniform(), u2 = rng.uniform();
        const Vec3 w = phase_sample(p, Vec3(0, 0, 1), u1, u2);
        const double t = std::acos(std::clamp(w.z, -1.0, 1.0)), t2 = t * t;
        s2 += t2;
        s4 += t2 * t2;
      }
      m2s.push_back(s2 / per);
      m4s.push_back(s4 / per);
    }
    const auto [m2, e2] = mean_and_error(m2s);
    const auto [m4, e4] = mean_and_error(m4s);
    EXPECT_NEAR(q.m2, m2, 5.0 * e2 + 1e-6 * m2) << phase_describe(p);
    EXPECT_NEAR(q.m4, m4, 5.0 * e4 + 1e-6 * m4) << phase_describe(p);
    EXPECT_LT(e2, 0.03 * m2);
    EXPECT_LT(e4, 0.05 * m4);
  }
}

TEST(GsaDelay, GammaLawCarriesTheWeightMomentsAndTheAbsorptionTilt) {
  const DeflectionMoments m = deflection_moments(HgPhase{0.9});
  for (double z : {0.25, 1.0, 3.0}) {
    const GammaDelayLaw g = gsa_delay_law(z, 1.0, 0.0, m);
    const DelayMoments d = compound_poisson_delay_moments(z, 1.0, m);
    EXPECT_NEAR(g.mean(), d.mean, 1e-12 * d.mean);
    EXPECT_NEAR(g.variance(), d.variance, 1e-12 * d.variance);
    const double inf = std::numeric_limits<double>::infinity();
    EXPECT_NEAR(g.within(0.0, inf), -std::expm1(-z), 1e-14);
    // Bins add up to the whole: the CSV's first, inner and last rows.
    const double e1 = 0.1 * g.mean(), e2 = g.mean(), e3 = 5.0 * g.mean();
    EXPECT_NEAR(g.within(0.0, e1) + g.within(e1, e2) + g.within(e2, e3) + g.within(e3, inf), g.weight, 1e-14);
    // With absorption a the weight is E[exp(-a s)] = exp(-a z) E[exp(-a tau)], whose log-derivative in a
    // is -(z + the tilted mean) and whose second is the tilted variance: finite differences.
    const double a = 0.05, h = 1e-4;
    auto lw = [&](double x) { return std::log(gsa_delay_law(z, 1.0, x, m).weight); };
    const GammaDelayLaw ga = gsa_delay_law(z, 1.0, a, m);
    EXPECT_NEAR(-(lw(a + h) - lw(a - h)) / (2.0 * h), z + ga.mean(), 1e-6 * (z + ga.mean()));
    EXPECT_NEAR((lw(a + h) - 2.0 * lw(a) + lw(a - h)) / (h * h), ga.variance(), 1e-3 * ga.variance());
  }
}

}  // namespace
}  // namespace nimbus
