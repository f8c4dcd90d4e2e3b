// The environment image (scene/env_map.h): orientation against Blender's equirectangular convention,
// the importance sampling (normalisation by an independent quadrature, sample-pdf = eval-pdf, a
// chi-square test of the sampled density against the luminance), and the spherical-harmonic moments
// against closed forms.
#include "scene/env_map.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/rng.h"
#include "core/sh.h"
#include "support/stats.h"

namespace nimbus {
namespace {

// A w x h map whose pixel (i, j) is f(i, j).
template <typename F>
EnvMap make_map(int w, int h, F&& f, const Transform& t = Transform(), double intensity = 1.0) {
  std::vector<float> rgb(size_t(w) * h * 3);
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      const Rgb c = f(i, j);
      for (int k = 0; k < 3; ++k) rgb[(size_t(j) * w + i) * 3 + k] = float(c[k]);
    }
  return EnvMap(w, h, std::move(rgb), t, intensity);
}

// A structured test map: a gradient, a bright "sun" block and a black band.
Rgb test_pixel(int i, int j) {
  if (j >= 20 && j < 22) return Rgb(0.0);
  Rgb c(0.2 + 0.01 * i, 0.3 + 0.02 * j, 0.5);
  if (i >= 10 && i < 13 && j >= 5 && j < 7) c = Rgb(80.0, 60.0, 40.0);
  return c;
}

TEST(EnvMapLatLong, BlenderOrientation) {
  // Cycles: u = 1/2 - atan2(y, x) / (2 pi), v = 1 - acos(z) / pi from the image's bottom, i.e. t = 1 - v
  // from its top.
  auto ll = direction_to_latlong(Vec3(1, 0, 0));
  EXPECT_NEAR(ll.u, 0.5, 1e-12);  // the centre looks along +x
  EXPECT_NEAR(ll.t, 0.5, 1e-12);
  ll = direction_to_latlong(Vec3(0, -1, 0));
  EXPECT_NEAR(ll.u, 0.75, 1e-12);  // u grows towards -y
  ll = direction_to_latlong(Vec3(0, 1, 0));
  EXPECT_NEAR(ll.u, 0.25, 1e-12);
  EXPECT_NEAR(direction_to_latlong(Vec3(0, 0, 1)).t, 0.0, 1e-12);  // the top row is +z
  EXPECT_NEAR(direction_to_latlong(Vec3(0, 0, -1)).t, 1.0, 1e-12);
  const Vec3 back = latlong_to_direction(0.0, 0.5);  // the image's left and right edges: -x
  EXPECT_NEAR(back.x, -1.0, 1e-12);
}

TEST(EnvMapLatLong, RoundTrip) {
  Rng rng(7, 0);
  for (int k = 0; k < 10000; ++k) {
    const double u = rng.uniform(), t = rng.uniform();
    const Vec3 w = latlong_to_direction(u, t);
    EXPECT_NEAR(w.length(), 1.0, 1e-12);
    const LatLong ll = direction_to_latlong(w);
    EXPECT_NEAR(std::remainder(ll.u - u, 1.0), 0.0, 1e-9);
    EXPECT_NEAR(ll.t, t, 1e-9);
  }
}

TEST(EnvMapSampling, SampleMatchesPdfAndRadiance) {
  const EnvMap map = make_map(32, 24, test_pixel, Transform::rotation(Vec3(1, 2, 3), 40.0));
  Rng rng(3, 0);
  for (int k = 0; k < 20000; ++k) {
    const EnvSample s = map.sample(rng.uniform(), rng.uniform());
    ASSERT_GT(s.pdf, 0.0);
    EXPECT_NEAR(s.wi.length(), 1.0, 1e-12);
    EXPECT_NEAR(map.pdf(s.wi), s.pdf, 1e-6 * s.pdf);
    const Rgb L = map.eval(s.wi);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(L[c], s.L[c], 1e-6 * (1.0 + L[c]));
    EXPECT_GT(luminance(s.L), 0.0);  // the black band is never drawn
  }
}

TEST(EnvMapSampling, PdfIntegratesToOne) {
  // Independent quadrature: a midpoint rule in (cos theta, phi) on a grid not aligned with the pixels,
  // in the world frame of a rotated map.
  const EnvMap map = make_map(32, 24, test_pixel, Transform::rotation(Vec3(0, 1, 1), 33.0));
  const int nz = 1201, nphi = 2403;
  double sum = 0.0;
  for (int a = 0; a < nz; ++a) {
    const double z = -1.0 + (a + 0.5) * 2.0 / nz, r = std::sqrt(1.0 - z * z);
    for (int b = 0; b < nphi; ++b) {
      const double phi = (b + 0.5) * 2.0 * kPi / nphi;
      sum += map.pdf(Vec3(r * std::cos(phi), r * std::sin(phi), z));
    }
  }
  sum *= (2.0 / nz) * (2.0 * kPi / nphi);
  EXPECT_NEAR(sum, 1.0, 2e-3);
}

TEST(EnvMapSampling, ChiSquareAgainstLuminance) {
  // Bins of 4 x 4 pixels (8 x 6 bins), found from the world direction by the test's own formulas; the
  // expected share of a bin is int Y dw over it (pixel luminance times the pixel's solid angle) over the
  // whole sphere. Pooled below 5 expected counts; fails below p = 1e-4.
  const int W = 32, H = 24, B = 4;
  const EnvMap map = make_map(W, H, test_pixel, Transform::rotation(Vec3(0, 0, 1), 90.0));
  std::vector<double> expected((W / B) * (H / B), 0.0), observed(expected.size(), 0.0);
  double total = 0.0;
  for (int j = 0; j < H; ++j)
    for (int i = 0; i < W; ++i) {
      const double solid = 2.0 * kPi / W * (std::cos(kPi * j / H) - std::cos(kPi * (j + 1) / H));
      const double e = luminance(test_pixel(i, j)) * solid;
      expected[(j / B) * (W / B) + i / B] += e;
      total += e;
    }
  const int n = 400000;
  for (double& e : expected) e *= n / total;
  Rng rng(11, 0);
  for (int k = 0; k < n; ++k) {
    const Vec3 w = map.sample(rng.uniform(), rng.uniform()).wi;
    // The map is turned 90 degrees about +z: its own +x looks along world +y.
    const Vec3 m(w.y, -w.x, w.z);
    double u = 0.5 - std::atan2(m.y, m.x) / (2.0 * kPi);
    if (u >= 1.0) u -= 1.0;
    const int i = std::min(W - 1, int(u * W)), j = std::min(H - 1, int(std::acos(m.z) / kPi * H));
    observed[(j / B) * (W / B) + i / B] += 1.0;
  }
  const test::ChiSquareResult r = test::chi_square(observed, expected);
  EXPECT_GT(r.p_value, 1e-4) << "chi2 " << r.chi2 << " dof " << r.dof;
  // Power: a density ignoring sin(theta) (uniform in t per luminance) is rejected.
  std::vector<double> wrong(expected.size(), 0.0);
  double wt = 0.0;
  for (int j = 0; j < H; ++j)
    for (int i = 0; i < W; ++i) {
      wrong[(j / B) * (W / B) + i / B] += luminance(test_pixel(i, j));
      wt += luminance(test_pixel(i, j));
    }
  for (double& e : wrong) e *= n / wt;
  EXPECT_LT(test::chi_square(observed, wrong).p_value, 1e-10);
}

TEST(EnvMapOrientation, BrightBlockLooksAlongItsDirection) {
  // A bright block at the image centre (+x), one at the top (+z), one at u = 3/4 (-y).
  auto bright_at = [](int ci, int cj) {
    return
        [=](int i, int j) { return std::abs(i - ci) <= 1 && std::abs(j - cj) <= 1 ? Rgb(100.0) : Rgb(0.0); };
  };
  const int W = 64, H = 32;
  struct Case {
    int i, j;
    Vec3 world;
  };
  for (const Case& c :
       {Case{32, 16, Vec3(1, 0, 0)}, Case{32, 0, Vec3(0, 0, 1)}, Case{48, 16, Vec3(0, -1, 0)}}) {
    const EnvMap map = make_map(W, H, bright_at(c.i, c.j));
    Vec3 mean(0.0);
    Rng rng(5, 0);
    for (int k = 0; k < 2000; ++k) mean += map.sample(rng.uniform(), rng.uniform()).wi / 2000.0;
    EXPECT_GT(dot(normalize(mean), c.world), 0.98) << c.i << " " << c.j;
    EXPECT_GT(max_component(map.eval(c.world)), 0.0);
    EXPECT_EQ(max_component(map.eval(-c.world)), 0.0);
  }
  // A rotation of 90 degrees about +z turns the centre (+x) to +y.
  const EnvMap turned = make_map(W, H, bright_at(32, 16), Transform::rotation(Vec3(0, 0, 1), 90.0));
  EXPECT_GT(max_component(turned.eval(Vec3(0, 1, 0))), 0.0);
  EXPECT_EQ(max_component(turned.eval(Vec3(1, 0, 0))), 0.0);
}

TEST(EnvMapSh, MomentsOfOnePlusCosine) {
  // L(w) = 1 + a . w (a: the map's +z in the world): int L Y_00 = sqrt(4 pi); by Funk-Hecke
  // int (a . w) Y_1m(w) dw = (4 pi / 3) Y_1m(a); every other moment is 0.
  const int W = 256, H = 128;
  const Transform t = Transform::rotation(Vec3(0, 1, 0), 90.0).then(Transform::rotation(Vec3(1, 1, 0), 25.0));
  const EnvMap map = make_map(
      W, H, [&](int, int j) { return Rgb(1.0 + std::cos(kPi * (j + 0.5) / H)); }, t);
  const std::vector<Rgb> m = map.sh_moments(3);
  const Vec3 a = t.vector(Vec3(0, 0, 1));
  double y[9];
  sh_eval(a, 3, y);
  for (int h = 0; h < 9; ++h) {
    const double exact = h == 0 ? std::sqrt(4.0 * kPi) : (h < 4 ? 4.0 * kPi / 3.0 * y[h] : 0.0);
    EXPECT_NEAR(m[h].x, exact, 2e-3) << "moment " << h;
  }
  EXPECT_NEAR(map.luminance_integral(), 4.0 * kPi, 1e-3);  // int (1 + a . w) dw
}

TEST(EnvMapSampling, BlackMapDrawsNothing) {
  const EnvMap map = make_map(8, 4, [](int, int) { return Rgb(0.0); });
  EXPECT_EQ(map.sample(0.3, 0.6).pdf, 0.0);
  EXPECT_EQ(map.pdf(Vec3(1, 0, 0)), 0.0);
}

}  // namespace
}  // namespace nimbus
