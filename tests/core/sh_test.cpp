// Real spherical harmonics: orthonormality by quadrature and the addition theorem; the lobe tail's
// extrapolation against the exact bands of a constant plus an HG lobe.
#include "core/sh.h"

#include <gtest/gtest.h>

#include <vector>

namespace nimbus {
namespace {

TEST(SphericalHarmonics, OrthonormalOnTheSphere) {
  const int bands = kShMaxBands, n = bands * bands;
  std::vector<double> gram(n * n, 0.0), y(n);
  // Midpoint rule in cos(theta) and phi (error ~1e-4 for these degrees).
  const int nt = 400, np = 400;
  for (int i = 0; i < nt; ++i) {
    const double z = -1.0 + (i + 0.5) * 2.0 / nt, r = std::sqrt(1.0 - z * z);
    for (int j = 0; j < np; ++j) {
      const double phi = (j + 0.5) * 2.0 * kPi / np;
      sh_eval(Vec3(r * std::cos(phi), r * std::sin(phi), z), bands, y.data());
      for (int a = 0; a < n; ++a)
        for (int b = 0; b < n; ++b) gram[a * n + b] += y[a] * y[b] * (2.0 / nt) * (2.0 * kPi / np);
    }
  }
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b) EXPECT_NEAR(gram[a * n + b], a == b ? 1.0 : 0.0, 1e-3) << a << " " << b;
}

TEST(SphericalHarmonics, AdditionTheorem) {
  const Vec3 a = normalize(Vec3(0.3, -0.5, 0.8)), b = normalize(Vec3(-0.7, 0.2, 0.1));
  double ya[kShMaxBands * kShMaxBands], yb[kShMaxBands * kShMaxBands];
  sh_eval(a, kShMaxBands, ya);
  sh_eval(b, kShMaxBands, yb);
  const double mu = dot(a, b);
  double p_prev = 1.0, p = mu;  // Legendre P_l(mu)
  for (int l = 0; l < kShMaxBands; ++l) {
    const double pl = l == 0 ? 1.0 : (l == 1 ? mu : p);
    double sum = 0.0;
    for (int h = l * l; h < (l + 1) * (l + 1); ++h) sum += ya[h] * yb[h];
    EXPECT_NEAR(sum, (2.0 * l + 1.0) / (4.0 * kPi) * pl, 1e-12) << l;
    if (l >= 1) {
      const double next = ((2.0 * l + 1.0) * mu * p - l * p_prev) / (l + 1.0);
      p_prev = p;
      p = next;
    }
  }
  // The poles (no division by sin(theta)).
  sh_eval(Vec3(0, 0, 1), kShMaxBands, ya);
  for (int h = 0; h < kShMaxBands * kShMaxBands; ++h) EXPECT_TRUE(std::isfinite(ya[h]));
}

// A constant a plus c HG(r) about d has the moments L_lm = a sqrt(4 pi) [l = 0] + c r^l Y_lm(d) (HG's Legendre
// series and the addition theorem). From its bands l <= 2 alone, sh_lobe_tail gives its bands 3 to 5 at any
// direction: compared with sum_m L_lm Y_lm(w) of the exact moments.
TEST(SphericalHarmonics, LobeTailIsExactForAnHgLobe) {
  const Vec3 d = normalize(Vec3(0.2, -0.6, 0.75));
  const double a = 0.3, c = 1.7;
  for (const double r : {0.3, 0.7, 0.9}) {
    double yd[kShMaxBands * kShMaxBands], L[kShMaxBands * kShMaxBands];
    sh_eval(d, kShMaxBands, yd);
    for (int l = 0; l < kShMaxBands; ++l)
      for (int h = l * l; h < (l + 1) * (l + 1); ++h) L[h] = c * std::pow(r, l) * yd[h];
    L[0] += a * std::sqrt(4.0 * kPi);
    for (const Vec3& w : {d, -d, normalize(Vec3(1.0, 0.3, -0.2)), normalize(Vec3(-0.4, -0.1, 0.9))}) {
      double y[kShMaxBands * kShMaxBands], t[kShMaxBands];
      sh_eval(w, kShMaxBands, y);
      sh_lobe_tail(L, y, t);
      for (int l = 0; l < 3; ++l) EXPECT_EQ(t[l], 0.0);
      for (int l = 3; l < kShMaxBands; ++l) {
        double exact = 0.0;
        for (int h = l * l; h < (l + 1) * (l + 1); ++h) exact += L[h] * y[h];
        EXPECT_NEAR(t[l], exact, 1e-12 * c) << "r " << r << " l " << l;
      }
    }
  }
  // No lobe where band 2 along band 1's direction is not positive: a constant plus a pure l = 1 term.
  double L[9] = {1.0, 0.2, -0.1, 0.3, 0.0, 0.0, 0.0, 0.0, 0.0}, y[9], t[kShMaxBands];
  sh_eval(normalize(Vec3(0.5, 0.5, 0.1)), 3, y);
  sh_lobe_tail(L, y, t);
  for (int l = 0; l < kShMaxBands; ++l) EXPECT_EQ(t[l], 0.0);
}

}  // namespace
}  // namespace nimbus
