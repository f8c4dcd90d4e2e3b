// Real spherical harmonics: orthonormality by quadrature and the addition theorem.
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

}  // namespace
}  // namespace nimbus
