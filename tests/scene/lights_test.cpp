// The spot, sphere and rectangle lights (scene/lights.h, scene/area_lights.h) against closed forms and
// independent quadratures: the spot's smooth edge, a sphere light's irradiance pi L (r/d)^2 cos, a
// rectangle light's irradiance by a midpoint rule over its area, what a ray sees of them, and where
// their photons leave.
#include "scene/lights.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/rng.h"
#include "scene/area_lights.h"
#include "support/stats.h"

namespace nimbus {
namespace {

// Cycles' spot edge (kernel/light/spot.h in Blender 3.4, written here from its description):
// smoothstep(0, 1, (cos - cos_half) / (blend (1 - cos_half))), without Cycles' extra cosine factor.
double reference_falloff(double cone_deg, double blend, double cos_a) {
  const double ch = std::cos(cone_deg * kPi / 360.0);
  if (cos_a <= ch) return 0.0;
  if (blend == 0.0) return 1.0;
  const double x = std::min(1.0, (cos_a - ch) / (blend * (1.0 - ch)));
  return x * x * (3.0 - 2.0 * x);
}

// A sun's disc: directions uniform in its cone (inside it, at the right mean cosine), weight its radiance
// times the cone's solid angle (the irradiance, to O(r^2)), and the light's precomputed constants give
// the same samples bit for bit.
TEST(DirectionalLight, DiscSamplesFillTheConeAndTheConstantsChangeNoBit) {
  DirectionalLight d;
  d.direction = normalize(Vec3(-0.75, -0.3, -0.55));
  d.irradiance = Rgb(3.4, 3.0, 2.0);
  d.angular_diameter_deg = 2.0;
  const Light light(d);
  const LightConstants k = light_constants(light);
  const double r = kPi / 180.0, cos_max = std::cos(r);
  EXPECT_EQ(k.cos_max, cos_max);
  Rng rng(3, 1);
  double mean_cos = 0.0;
  constexpr int kN = 20000;
  for (int n = 0; n < kN; ++n) {
    const double u1 = rng.uniform(), u2 = rng.uniform();
    LightSample a, b;
    ASSERT_TRUE(sample_light(light, Vec3(1, 2, 3), u1, u2, &a));
    ASSERT_TRUE(sample_light(light, k, Vec3(1, 2, 3), u1, u2, &b));
    for (int c = 0; c < 3; ++c) {
      EXPECT_EQ(a.wi[c], b.wi[c]);
      EXPECT_EQ(a.weight[c], b.weight[c]);
      EXPECT_NEAR(a.weight[c], d.irradiance[c] * 2.0 * (1.0 - cos_max) / (std::sin(r) * std::sin(r)), 1e-12);
    }
    EXPECT_GE(dot(a.wi, -d.direction), cos_max - 1e-12);
    mean_cos += dot(a.wi, -d.direction) / kN;
  }
  EXPECT_NEAR(mean_cos, 0.5 * (1.0 + cos_max), 2e-6);
}

TEST(SpotLight, FalloffIsOneInsideZeroOutsideAndSmoothstepAcrossTheBlend) {
  SpotLight s;
  s.cone_angle_deg = 60.0;
  s.blend = 0.4;
  const double ch = std::cos(kPi / 6.0), band = 0.4 * (1.0 - ch);
  EXPECT_EQ(spot_falloff(s, 1.0), 1.0);
  EXPECT_EQ(spot_falloff(s, ch + band + 1e-9), 1.0);
  EXPECT_EQ(spot_falloff(s, ch - 1e-9), 0.0);
  EXPECT_EQ(spot_falloff(s, -1.0), 0.0);
  EXPECT_NEAR(spot_falloff(s, ch + 0.5 * band), 0.5, 1e-12);
  EXPECT_NEAR(spot_falloff(s, ch + 0.25 * band), 0.15625, 1e-12);  // 3/16 - 2/64
  for (double c = ch - 0.05; c < 1.0; c += 0.001)
    EXPECT_NEAR(spot_falloff(s, c), reference_falloff(60.0, 0.4, c), 1e-12);
  s.blend = 0.0;  // a hard edge
  EXPECT_EQ(spot_falloff(s, ch + 1e-9), 1.0);
  s.cone_angle_deg = 180.0;  // a hemisphere
  EXPECT_EQ(spot_falloff(s, 1e-6), 1.0);
  EXPECT_EQ(spot_falloff(s, -1e-6), 0.0);
}

TEST(SpotLight, SampleIsThePointLightTimesTheFalloff) {
  SpotLight s;
  s.position = Vec3(0, 0, 2);
  s.direction = Vec3(0, 0, -1);
  s.intensity = Rgb(2.0, 3.0, 4.0);
  s.cone_angle_deg = 40.0;
  s.blend = 0.5;
  for (double x = 0.0; x < 1.5; x += 0.05) {
    const Vec3 p(x, 0.3 * x, 0.0);
    LightSample ls;
    const double d2 = (s.position - p).length2();
    const double f = reference_falloff(40.0, 0.5, 2.0 / std::sqrt(d2));
    ASSERT_EQ(sample_light(Light(s), p, 0.3, 0.7, &ls), f > 0.0);
    if (f <= 0.0) continue;
    EXPECT_NEAR(ls.weight.y, 3.0 * f / d2, 1e-12);
    EXPECT_NEAR(ls.distance, std::sqrt(d2), 1e-12);
  }
}

// Irradiance at p (normal n) from one light by its own sampling: mean and standard error.
test::MeanAccumulator irradiance(const Light& light, const Vec3& p, const Vec3& n, int count) {
  test::MeanAccumulator acc;
  Rng rng(7, 3);
  for (int i = 0; i < count; ++i) {
    LightSample ls;
    const double u1 = rng.uniform(), u2 = rng.uniform();
    acc.add(sample_light(light, p, u1, u2, &ls) ? ls.weight.x * std::max(0.0, dot(n, ls.wi)) : 0.0);
  }
  return acc;
}

TEST(SphereLight, IrradianceMatchesTheClosedForm) {
  // E = pi L (r / d)^2 cos(theta) while the whole cap lies above the horizon.
  SphereLight s;
  s.center = Vec3(0.3, -0.2, 2.0);
  s.radius = 0.6;
  s.radiance = Rgb(1.7);
  const Vec3 p(0.0);
  const double d = length(s.center);
  const Vec3 axis = s.center / d;
  for (double theta_deg : {0.0, 30.0, 60.0}) {
    const Vec3 n = spherical_direction(std::cos(theta_deg * kPi / 180.0), 1.0, axis);
    const double exact = kPi * 1.7 * (0.6 / d) * (0.6 / d) * std::cos(theta_deg * kPi / 180.0);
    const test::MeanAccumulator e = irradiance(s, p, n, 20000);
    EXPECT_NEAR(e.mean, exact, 5.0 * e.stderr_mean() + 1e-12) << theta_deg;
    EXPECT_LT(e.stderr_mean(), 0.01 * exact);  // the test has power
  }
  // Facing it, the estimate has no noise at all: every sample's cosine... is near 1; inside: nothing.
  LightSample ls;
  EXPECT_FALSE(sample_light(Light(s), s.center + Vec3(0.1, 0, 0), 0.5, 0.5, &ls));
}

TEST(SphereLight, SampledPointsLieOnTheNearSide) {
  SphereLight s;
  s.center = Vec3(1, 2, 3);
  s.radius = 0.5;
  Rng rng(1, 1);
  const Vec3 p(0.2, -0.4, 0.1);
  for (int i = 0; i < 2000; ++i) {
    LightSample ls;
    ASSERT_TRUE(sample_light(Light(s), p, rng.uniform(), rng.uniform(), &ls));
    const Vec3 q = p + ls.wi * ls.distance;
    EXPECT_NEAR(length(q - s.center), 0.5, 1e-9);
    EXPECT_LT(dot(q - s.center, ls.wi), 1e-9);  // the surface faces p there
    double t = 0.0;
    Rgb L;
    ASSERT_TRUE(hit_area_light(Light(s), p, ls.wi, 1e30, &t, &L));
    EXPECT_NEAR(t, ls.distance, 1e-9);
  }
}

TEST(RectangleLight, IrradianceMatchesAMidpointQuadrature) {
  RectangleLight r;
  r.center = Vec3(0.4, 0.1, 1.5);
  r.normal = normalize(Vec3(0.2, 0.1, -1.0));
  r.up = normalize(cross(r.normal, Vec3(1, 0, 0)));
  r.width = 1.2;
  r.height = 0.7;
  r.radiance = Rgb(2.5);
  const Vec3 ew = normalize(cross(r.normal, r.up));
  // Points far (by area: under 1e-3 sr), at a middle distance and close (by solid angle), several normals.
  for (const Vec3& p : {Vec3(0.0), Vec3(0.5, 0.0, 1.3), Vec3(3.0, -1.0, -30.0)}) {
    for (const Vec3& n : {Vec3(0, 0, 1), normalize(Vec3(0.5, 0.2, 1.0)), normalize(Vec3(-0.3, 0.0, 1.0))}) {
      // E = int L cos_p cos_l / d^2 dA, 600 x 600 midpoints.
      const int m = 600;
      double exact = 0.0;
      for (int i = 0; i < m; ++i)
        for (int j = 0; j < m; ++j) {
          const Vec3 q =
              r.center + ew * (((i + 0.5) / m - 0.5) * r.width) + r.up * (((j + 0.5) / m - 0.5) * r.height);
          const Vec3 v = q - p;
          const double d2 = v.length2(), dd = std::sqrt(d2);
          exact += 2.5 * std::max(0.0, dot(n, v) / dd) * std::max(0.0, -dot(r.normal, v) / dd) / d2;
        }
      exact *= r.width * r.height / (double(m) * m);
      const test::MeanAccumulator e = irradiance(r, p, n, 40000);
      EXPECT_NEAR(e.mean, exact, 5.0 * e.stderr_mean() + 1e-4 * exact) << p.z << " " << n.x;
      EXPECT_LT(e.stderr_mean(), 0.01 * exact);
    }
  }
  // By solid angle every sample lies on the rectangle and weighs L times the solid angle (here the
  // quadrature of cos_l / d^2 dA), the same for every sample.
  const Vec3 p(0.5, 0.0, 1.3);
  double solid_angle = 0.0;
  const int m = 600;
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) {
      const Vec3 v =
          r.center + ew * (((i + 0.5) / m - 0.5) * r.width) + r.up * (((j + 0.5) / m - 0.5) * r.height) - p;
      solid_angle += -dot(r.normal, v) / std::pow(v.length2(), 1.5);
    }
  solid_angle *= r.width * r.height / (double(m) * m);
  Rng rng(2, 2);
  for (int i = 0; i < 1000; ++i) {
    LightSample ls;
    ASSERT_TRUE(sample_light(Light(r), p, rng.uniform(), rng.uniform(), &ls));
    const Vec3 q = p + ls.wi * ls.distance - r.center;
    EXPECT_NEAR(dot(q, r.normal), 0.0, 1e-9);
    EXPECT_LE(std::abs(dot(q, ew)), 0.6 + 1e-9);
    EXPECT_LE(std::abs(dot(q, r.up)), 0.35 + 1e-9);
    EXPECT_NEAR(ls.weight.x, 2.5 * solid_angle, 1e-4 * 2.5 * solid_angle);
  }
  // One-sided: nothing reaches a point behind it.
  LightSample ls;
  EXPECT_FALSE(sample_light(Light(r), r.center + r.normal * -0.5, 0.3, 0.6, &ls));
  double t = 0.0;
  Rgb L;
  EXPECT_TRUE(hit_area_light(Light(r), Vec3(0.4, 0.1, 0.0), Vec3(0, 0, 1), 1e30, &t, &L));
  EXPECT_FALSE(hit_area_light(Light(r), Vec3(0.4, 0.1, 3.0), Vec3(0, 0, -1), 1e30, &t, &L));  // its back
  EXPECT_FALSE(hit_area_light(Light(r), Vec3(2.0, 0.1, 0.0), Vec3(0, 0, 1), 1e30, &t, &L));   // beside it
}

TEST(RectangleLight, SamplesStayFiniteNextToTheLight) {
  // Just in front of the plane, inside and outside the rectangle's outline: finite weights; right in
  // front of the centre the irradiance is the closed form (tending to pi L).
  RectangleLight r;
  r.center = Vec3(0, 0, 1);
  r.normal = Vec3(0, 0, -1);
  r.up = Vec3(0, 1, 0);
  r.width = 2.0;
  r.height = 2.0;
  r.radiance = Rgb(1.0);
  Rng rng(3, 3);
  for (const Vec3& p : {Vec3(0, 0, 1 - 1e-9), Vec3(0.3, -0.2, 1 - 1e-6), Vec3(2.0, 0.0, 1 - 1e-7)})
    for (int i = 0; i < 1000; ++i) {
      LightSample ls;
      if (!sample_light(Light(r), p, rng.uniform(), rng.uniform(), &ls)) continue;
      ASSERT_TRUE(is_finite(ls.weight) && std::isfinite(ls.distance) && is_finite(ls.wi));
    }
  // The closed form below the centre: four corner rectangles of 1 x 1 at height c, each the form factor
  // (1 / 2 pi) [A / sqrt(1 + A^2) atan(B / sqrt(1 + A^2)) + (A <-> B)], A = B = 1 / c, times pi L.
  const double c = 1e-3, A = 1.0 / c, s1 = std::sqrt(1.0 + A * A);
  const double exact = 4.0 * kPi * (2.0 * A / s1 * std::atan(A / s1)) / (2.0 * kPi);
  const test::MeanAccumulator e = irradiance(r, Vec3(0, 0, 1 - c), Vec3(0, 0, 1), 20000);
  EXPECT_NEAR(e.mean, exact, 5.0 * e.stderr_mean());
  EXPECT_LT(e.stderr_mean(), 0.005 * exact);
}

TEST(AreaLights, PhotonsCarryTheLightsPowerOutwards) {
  SphereLight s;
  s.center = Vec3(1, 0, 0);
  s.radius = 0.3;
  s.radiance = Rgb(2.0);
  RectangleLight r;
  r.width = 2.0;
  r.height = 0.5;
  r.radiance = Rgb(3.0);
  Rng rng(4, 4);
  const int n = 20000;
  double sphere_power = 0.0, rect_power = 0.0, cos_sum = 0.0;
  for (int i = 0; i < n; ++i) {
    Vec3 x, w;
    Rgb power;
    ASSERT_TRUE(
        emit_area_photon(s, n, rng.uniform(), rng.uniform(), rng.uniform(), rng.uniform(), &x, &w, &power));
    EXPECT_NEAR(length(x - s.center), 0.3, 1e-12);
    const double c = dot(w, (x - s.center) / 0.3);
    EXPECT_GT(c, 0.0);
    cos_sum += c;
    sphere_power += power.x;
    ASSERT_TRUE(
        emit_area_photon(r, n, rng.uniform(), rng.uniform(), rng.uniform(), rng.uniform(), &x, &w, &power));
    EXPECT_GT(dot(w, r.normal), 0.0);
    EXPECT_LE(std::abs(dot(x - r.center, r.up)), 0.25 + 1e-12);
    rect_power += power.x;
  }
  EXPECT_NEAR(sphere_power, 4.0 * kPi * kPi * 0.09 * 2.0, 1e-9);  // 4 pi^2 r^2 L
  EXPECT_NEAR(rect_power, kPi * 1.0 * 3.0, 1e-9);                 // pi A L
  EXPECT_NEAR(cos_sum / n, 2.0 / 3.0, 0.01);                      // cosine-weighted: <cos> = 2/3
}

}  // namespace
}  // namespace nimbus
