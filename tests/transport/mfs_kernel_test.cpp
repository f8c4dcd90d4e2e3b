// The corrected MFS kernel: normalisation by numerical integration, limits, symmetry, stability, and a
// Feynman-Kac random walk that checks the total and both marginals independently of the algebra.
#include "transport/mfs_kernel.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/math.h"
#include "core/rng.h"
#include "nimbus/error.h"
#include "support/stats.h"

namespace nimbus {
namespace {

struct Case {
  double z, b, a, theta2;
};
const Case kKernelCases[] = {
    {1.0, 1.0, 0.0, 0.01}, {10.0, 1.0, 0.01, 0.01}, {30.0, 1.0, 0.1, 0.02}, {3.0, 2.0, 0.5, 0.005}};

// 4-D trapezoid over (r, v) of the fixed-axis kernel for a source along the axis.
double integrate_fixed_axis(const MfsScales& s, const GaussianBeam& g) {
  const int n = 48;
  const double sv = std::sqrt(g.var_angle), sr = std::sqrt(g.var_radius);
  const double hv = 12.0 * sv / n, hr = 12.0 * sr / n;
  double sum = 0.0;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j)
      for (int k = 0; k <= n; ++k)
        for (int l = 0; l <= n; ++l) {
          const Vec2 r(-6.0 * sr + i * hr, -6.0 * sr + j * hr), v(-6.0 * sv + k * hv, -6.0 * sv + l * hv);
          sum += mfs_fixed_axis(s, r, v, Vec2(0.0, 0.0));
        }
  return sum * hv * hv * hr * hr;
}

TEST(MfsKernel, IntegralOverPlaneAndAngleIsWOverCosh) {
  for (const Case& c : kKernelCases) {
    const MfsScales s = mfs_scales(GaussianModel::Mfs, c.z, c.b * c.z, c.a * c.z, c.theta2);
    const GaussianBeam g = gaussian_beam(GaussianModel::Mfs, c.z, c.b * c.z, c.a * c.z, c.theta2);
    const double L = 1.0 / std::sqrt(c.a * s.T);
    const double expected = std::exp(-c.a * c.z) * (1.0 - std::exp(-c.b * c.z)) / std::cosh(c.z / L);
    EXPECT_NEAR(integrate_fixed_axis(s, g), expected, 1e-6 * expected) << "z=" << c.z << " a=" << c.a;
    EXPECT_NEAR(g.total, expected, 1e-12 * expected);
  }
}

TEST(MfsKernel, AngularMarginalIsGaussianWithVarianceTLtanhx) {
  // Integrate over the plane at a few directions: exp(-v^2 / (2 var)) / (2 pi var) * total.
  const Case c{10.0, 1.0, 0.05, 0.01};
  const MfsScales s = mfs_scales(GaussianModel::Mfs, c.z, c.b * c.z, c.a * c.z, c.theta2);
  const GaussianBeam g = gaussian_beam(GaussianModel::Mfs, c.z, c.b * c.z, c.a * c.z, c.theta2);
  const double T = s.T, L = 1.0 / std::sqrt(c.a * T);
  EXPECT_NEAR(g.var_angle, T * L * std::tanh(c.z / L), 1e-12 * g.var_angle);
  const int n = 160;
  const double sr = std::sqrt(g.var_radius), h = 16.0 * sr / n;
  for (double v_over_sigma : {0.0, 1.0, 2.5}) {
    const Vec2 v(v_over_sigma * std::sqrt(g.var_angle), 0.0);
    double sum = 0.0;
    for (int i = 0; i <= n; ++i)
      for (int j = 0; j <= n; ++j)
        sum += mfs_fixed_axis(s, Vec2(-8.0 * sr + i * h, -8.0 * sr + j * h), v, Vec2(0.0, 0.0));
    const double expected = g.angular(v.x);
    EXPECT_NEAR(sum * h * h, expected, 1e-6 * g.angular(0.0));
  }
}

TEST(MfsKernel, ShortAndLongPathLimits) {
  // z << L: angular variance T z, spatial variance T z^3 / 3 (the notes' corrected section 1).
  {
    const MfsScales s = mfs_scales(GaussianModel::Mfs, 2.0, 2.0, 1e-7, 0.01);
    const GaussianBeam g = gaussian_beam(GaussianModel::Mfs, 2.0, 2.0, 1e-7, 0.01);
    EXPECT_LT(s.x, 1e-3);
    EXPECT_NEAR(g.var_angle / (s.T * 2.0), 1.0, 1e-6);
    EXPECT_NEAR(g.var_radius / (s.T * 8.0 / 3.0), 1.0, 1e-6);
    EXPECT_NEAR(g.cov / (s.T * 4.0 / 2.0), 1.0, 1e-6);
  }
  // z >> L: frozen angular width T L = sqrt(theta2 b / a); diffuse attenuation K = a + sqrt(a theta2 b).
  {
    const double a = 0.1, b = 1.0, th2 = 0.01, z = 400.0, dz = 1e-3;
    const GaussianBeam g = gaussian_beam(GaussianModel::Mfs, z, b * z, a * z, th2);
    EXPECT_NEAR(g.var_angle, std::sqrt(th2 * b / a), 1e-9);
    const GaussianBeam g2 = gaussian_beam(GaussianModel::Mfs, z + dz, b * (z + dz), a * (z + dz), th2);
    const double K = -(std::log(g2.total) - std::log(g.total)) / dz;
    EXPECT_NEAR(K, a + std::sqrt(a * th2 * b), 1e-6);
  }
}

TEST(MfsKernel, DolinAndTes87Forms) {
  const GaussianBeam d = gaussian_beam(GaussianModel::Dolin, 5.0, 5.0, 0.5, 0.01);
  EXPECT_NEAR(d.var_angle, 0.01 * 5.0, 1e-14);
  EXPECT_NEAR(d.var_radius, 0.01 * 125.0 / 3.0, 1e-12);
  EXPECT_NEAR(d.total, std::exp(-0.5) * (1.0 - std::exp(-5.0)), 1e-14);
  // Tes87 with a = 0 reduces to Dolin; with a > 0 it is the oscillator kernel with T = theta2 b.
  const GaussianBeam t0 = gaussian_beam(GaussianModel::Tes87, 5.0, 5.0, 0.0, 0.01);
  EXPECT_NEAR(t0.var_angle, d.var_angle, 1e-14);
  EXPECT_NEAR(t0.var_radius, d.var_radius, 1e-12);
  const GaussianBeam t = gaussian_beam(GaussianModel::Tes87, 5.0, 5.0, 0.5, 0.01);
  const double ell = 1.0 / std::sqrt(0.01 * 0.1 * 1.0);
  EXPECT_NEAR(t.var_angle, 0.01 * ell * std::tanh(5.0 / ell), 1e-12);
}

TEST(MfsKernel, SymmetryAndPaperFormMatchesFixedAxisWithoutAbsorption) {
  const MfsScales s = mfs_scales(GaussianModel::Mfs, 4.0, 4.0, 0.4, 0.01);
  const Vec2 g1(0.05, -0.02), g2(-0.01, 0.07);
  // Reciprocity: swapping arrival and departure directions.
  EXPECT_NEAR(mfs_green(s, g1, g2), mfs_green(s, g2, g1), 1e-12 * mfs_green(s, g1, g2));
  // Rotation about the axis.
  const double c = std::cos(0.7), sn = std::sin(0.7);
  auto rot = [&](const Vec2& v) { return Vec2(c * v.x - sn * v.y, sn * v.x + c * v.y); };
  EXPECT_NEAR(mfs_green(s, rot(g1), rot(g2)), mfs_green(s, g1, g2), 1e-12 * mfs_green(s, g1, g2));
  EXPECT_NEAR(mfs_fixed_axis(s, rot(Vec2(0.1, 0.2)), rot(g1), rot(g2)),
              mfs_fixed_axis(s, Vec2(0.1, 0.2), g1, g2), 1e-12 * mfs_fixed_axis(s, Vec2(0.1, 0.2), g1, g2));
  // Without absorption the tilted-axis (paper) and fixed-axis actions agree exactly:
  // gamma = v - r/z, gamma' = v0 - r/z.
  const double z = 4.0;
  const MfsScales s0 = mfs_scales(GaussianModel::Mfs, z, 4.0, 0.0, 0.01);
  const Vec2 r(0.15, -0.1), v(0.03, 0.02), v0(-0.01, 0.01);
  const double fixed = mfs_fixed_axis(s0, r, v, v0);
  EXPECT_NEAR(mfs_green(s0, v - r / z, v0 - r / z), fixed, 1e-10 * fixed);
}

TEST(MfsKernel, NumericallyStableEverywhere) {
  // h(x): series and closed form agree where they meet, and match long-double arithmetic.
  for (double x : {1e-8, 1e-3, 0.05, 0.0999, 0.1, 0.1001, 0.5, 3.0, 50.0}) {
    const long double lx = x;
    const long double ref =
        x < 1e-2 ? lx * lx * lx / 12.0L - lx * lx * lx * lx * lx / 120.0L : lx - 2.0L * std::tanh(lx / 2.0L);
    EXPECT_NEAR(mfs_h(x) / double(ref), 1.0, 1e-12) << x;
  }
  EXPECT_NEAR(mfs_h_over_x3(0.0), 1.0 / 12.0, 1e-16);
  // Extremes: a -> 0, b z -> 0, b z huge, z / L huge.  All finite, non-negative, no NaN.
  const double params[][4] = {{1.0, 1.0, 0.0, 0.01},    {1.0, 1e-12, 0.0, 0.01}, {1.0, 1e-12, 1e-12, 0.01},
                              {1e3, 1e3, 0.0, 0.01},    {1e4, 1e4, 1e3, 0.01},   {1.0, 1e3, 1e3, 0.5},
                              {1e-6, 1e-6, 1e-9, 1e-4}, {5.0, 5.0, 1e-300, 0.01}};
  for (const auto& p : params)
    for (GaussianModel m : {GaussianModel::Dolin, GaussianModel::Tes87, GaussianModel::Mfs}) {
      const MfsScales s = mfs_scales(m, p[0], p[1], p[2], p[3]);
      const GaussianBeam g = gaussian_beam(m, p[0], p[1], p[2], p[3]);
      for (double v :
           {g.total, g.var_angle, g.var_radius, g.cov, mfs_green(s, Vec2(0.01, 0.0), Vec2(0.0, 0.0)),
            mfs_fixed_axis(s, Vec2(0.0, 0.0), Vec2(0.0, 0.0), Vec2(0.0, 0.0))}) {
        EXPECT_TRUE(std::isfinite(v) && v >= 0.0) << p[0] << " " << p[1] << " " << p[2];
      }
    }
  // Continuous across the x = 1e-4 switch of the hyperbolic helpers.
  const double th2 = 0.01;
  const GaussianBeam lo =
      gaussian_beam(GaussianModel::Mfs, 1.0, 1.0, 0.99998e-8 / (th2 / (1 - std::exp(-1.0))), th2);
  const GaussianBeam hi =
      gaussian_beam(GaussianModel::Mfs, 1.0, 1.0, 1.00002e-8 / (th2 / (1 - std::exp(-1.0))), th2);
  EXPECT_NEAR(lo.var_radius / hi.var_radius, 1.0, 1e-9);
  EXPECT_THROW(mfs_scales(GaussianModel::Mfs, 0.0, 1.0, 0.0, 0.01), Error);
  EXPECT_THROW(mfs_scales(GaussianModel::Mfs, 1.0, -1.0, 0.0, 0.01), Error);
  EXPECT_THROW(mfs_scales(GaussianModel::Mfs, 1.0, 1.0, 0.0, 0.0), Error);
}

// Feynman-Kac: the kernel's path integral is a Brownian motion gamma(s) with per-component variance
// T s, killed at rate (a/2) |gamma|^2 (the path-lengthening absorption).  Its survival is 1 / cosh x,
// and the weighted moments of gamma(z) and int gamma ds are the angular and spatial variances.
TEST(MfsKernel, RandomWalkReproducesTotalAndMarginals) {
  const double z = 10.0, b = 1.0, a = 0.05, th2 = 0.01;
  const MfsScales s = mfs_scales(GaussianModel::Mfs, z, b * z, a * z, th2);
  const GaussianBeam g = gaussian_beam(GaussianModel::Mfs, z, b * z, a * z, th2);
  const int steps = 400, walks = 20000;
  const double ds = z / steps, sd = std::sqrt(s.T * ds);
  test::MeanAccumulator w_acc, v2_acc, r2_acc;
  Rng rng(7, 1);
  for (int w = 0; w < walks; ++w) {
    double gx = 0, gy = 0, rx = 0, ry = 0, action = 0;
    for (int i = 0; i < steps; ++i) {
      const double u1 = 1.0 - rng.uniform(), u2 = rng.uniform();
      const double rad = std::sqrt(-2.0 * std::log(u1));
      const double nx = gx + sd * rad * std::cos(2 * kPi * u2), ny = gy + sd * rad * std::sin(2 * kPi * u2);
      action += 0.5 * a * ds * 0.5 * (gx * gx + gy * gy + nx * nx + ny * ny);  // trapezoid
      rx += 0.5 * ds * (gx + nx);
      ry += 0.5 * ds * (gy + ny);
      gx = nx;
      gy = ny;
    }
    const double wt = std::exp(-action);
    w_acc.add(wt);
    v2_acc.add(wt * 0.5 * (gx * gx + gy * gy));
    r2_acc.add(wt * 0.5 * (rx * rx + ry * ry));
  }
  const double surv = g.total / s.W;
  EXPECT_NEAR(w_acc.mean, surv, 5.0 * w_acc.stderr_mean() + 1e-4);
  EXPECT_NEAR(v2_acc.mean / surv, g.var_angle, 5.0 * v2_acc.stderr_mean() / surv + 1e-3 * g.var_angle);
  EXPECT_NEAR(r2_acc.mean / surv, g.var_radius, 5.0 * r2_acc.stderr_mean() / surv + 1e-3 * g.var_radius);
}

}  // namespace
}  // namespace nimbus
