// Phase functions: normalisation by independent quadrature, mean cosine, and chi-square tests of
// every sampler against its own eval (sample pdf == eval pdf).
#include "media/phase.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/rng.h"
#include "nimbus/error.h"
#include "support/stats.h"

namespace nimbus {
namespace {

// Integral over the sphere of p(cos theta) by midpoint rule in theta, refined near the forward peak.
double phase_sphere_integral(const Phase& p, double weight_power = 0.0) {
  double sum = 0.0;
  const int n = 400000;
  for (int i = 0; i < n; ++i) {
    // theta = pi * s^2 concentrates nodes near 0 (forward peaks).
    const double s = (i + 0.5) / n;
    const double th = kPi * s * s, dth = 2.0 * kPi * s / n;
    sum += phase_eval(p, std::cos(th)) * std::pow(std::cos(th), weight_power) * std::sin(th) * dth;
  }
  return 2.0 * kPi * sum;
}

std::vector<Phase> all_phases() {
  std::vector<double> th, v;
  for (int i = 0; i <= 180; ++i) {
    th.push_back(kPi * i / 180.0);
    v.push_back(std::exp(-20.0 * th.back()) + 0.05 + 0.02 * std::cos(th.back()));
  }
  return {IsotropicPhase{},
          HgPhase{0.0},
          HgPhase{0.3},
          HgPhase{0.85},
          HgPhase{-0.7},
          HgPhase{0.99},
          DoubleHgPhase{0.9, -0.3, 0.8},
          make_gauss_phase(0.01),
          make_gauss_phase(0.3),
          make_gauss_phase(3.0),
          make_tabulated_phase("test", th, v)};
}

TEST(Phase, NormalisedOnTheSphere) {
  for (const Phase& p : all_phases()) {
    EXPECT_NEAR(phase_sphere_integral(p), 1.0, 2e-4) << phase_describe(p);
  }
}

TEST(Phase, MeanCosineMatchesQuadrature) {
  for (const Phase& p : all_phases()) {
    EXPECT_NEAR(phase_mean_cosine(p), phase_sphere_integral(p, 1.0), 2e-4) << phase_describe(p);
  }
}

TEST(Phase, HgClosedFormAgainstKnownValues) {
  // At g = 0 HG is isotropic; forward value (1 + g) / (4 pi (1 - g)^2).
  EXPECT_NEAR(hg_eval(0.3, 0.0), kInv4Pi, 1e-15);
  EXPECT_NEAR(hg_eval(1.0, 0.5), 1.5 / (4.0 * kPi * 0.25), 1e-12);
  EXPECT_NEAR(hg_eval(-1.0, 0.5), 0.5 / (4.0 * kPi * 2.25), 1e-12);
}

// Chi-square of sampled directions against eval, binned in (theta via u = ((1 - cos)/2)^(1/4), phi).
TEST(Phase, SamplersMatchEvalChiSquare) {
  const int n_theta = 40, n_phi = 8;
  const int samples = 400000;
  const Vec3 wi = normalize(Vec3(0.3, -0.5, 0.8));
  const Frame frame(wi);
  for (const Phase& p : all_phases()) {
    std::vector<double> observed(n_theta * n_phi, 0.0), expected(n_theta * n_phi, 0.0);
    Rng rng(7, 11);
    for (int i = 0; i < samples; ++i) {
      const Vec3 wo = phase_sample(p, wi, rng.uniform(), rng.uniform());
      ASSERT_NEAR(length(wo), 1.0, 1e-9);
      const Vec3 l = frame.to_local(wo);
      const double u = std::pow(std::clamp((1.0 - l.z) * 0.5, 0.0, 1.0), 0.25);
      double phi = std::atan2(l.y, l.x);
      if (phi < 0) phi += 2.0 * kPi;
      const int it = std::min(n_theta - 1, int(u * n_theta));
      const int ip = std::min(n_phi - 1, int(phi / (2.0 * kPi) * n_phi));
      observed[it * n_phi + ip] += 1.0;
    }
    // Expected counts: integrate eval over each cell (u -> cos = 1 - 2 u^4).
    for (int it = 0; it < n_theta; ++it) {
      double prob = 0.0;
      const int sub = 2000;
      for (int k = 0; k < sub; ++k) {
        const double u0 = (it + double(k) / sub) / n_theta, u1 = (it + double(k + 1) / sub) / n_theta;
        const double c0 = 1.0 - 2.0 * std::pow(u0, 4), c1 = 1.0 - 2.0 * std::pow(u1, 4);
        prob += phase_eval(p, 0.5 * (c0 + c1)) * (c0 - c1) * 2.0 * kPi;
      }
      for (int ip = 0; ip < n_phi; ++ip) expected[it * n_phi + ip] = prob / n_phi * samples;
    }
    const auto r = test::chi_square(observed, expected);
    EXPECT_GT(r.p_value, 1e-4) << phase_describe(p) << " chi2=" << r.chi2 << " dof=" << r.dof;
  }
}

TEST(Phase, TabulatedRejectsMalformedTables) {
  EXPECT_THROW(make_tabulated_phase("x", {0.0}, {1.0}), Error);
  EXPECT_THROW(make_tabulated_phase("x", {0.0, 1.0}, {1.0, 1.0}), Error);
  EXPECT_THROW(make_tabulated_phase("x", {0.0, kPi}, {1.0, -1.0}), Error);
  EXPECT_THROW(make_gauss_phase(-1.0), Error);
}

}  // namespace
}  // namespace nimbus
