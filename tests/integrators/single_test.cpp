// `single` against the reference restricted to one scattering event (pathtrace, max_events = 1).
#include "integrators/single.h"

#include <gtest/gtest.h>

#include "integrators/pathtrace.h"
#include "support/scenes.h"
#include "support/stats.h"

namespace nimbus {
namespace {

TEST(Single, MatchesPathTracerWithOneEvent) {
  const Scene scene = test::scene_from_json("{" + test::camera_json() + R"(,
    "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": [1.0, 2.0, 4.0],
               "sigma_a": 0.1, "phase": {"type": "hg", "g": 0.7}},
              {"shape": {"type": "box", "min": [-0.3, -2, -0.3], "max": [0.3, 0.2, 0.3]}, "sigma_s": 1.5,
               "phase": {"type": "isotropic"}}],
    "lights": [{"type": "directional", "direction": [0.3, 1, -0.6], "irradiance": 2.0},
               {"type": "point", "position": [1, -2, 1], "intensity": 3.0},
               {"type": "environment", "radiance": [0.2, 0.3, 0.5]}]})");
  const SceneContext ctx(scene);
  const PathTracer pt(ctx, 1);
  const SingleScatter single(ctx, SingleSettings{0.05, 1});
  for (const Vec3& d : {Vec3(0, 1, 0), normalize(Vec3(0.2, 1, 0.1)), normalize(Vec3(-0.15, 1, -0.2))}) {
    test::MeanAccumulator a[3], b[3];
    for (int i = 0; i < 5000; ++i) {
      Rng r1(1, i), r2(2, i);
      const Rgb la = pt.Li({Vec3(0, -4, 0), d}, r1), lb = single.Li({Vec3(0, -4, 0), d}, r2);
      for (int k = 0; k < 3; ++k) {
        a[k].add(la[k]);
        b[k].add(lb[k]);
      }
    }
    for (int k = 0; k < 3; ++k) {
      const double tol = 5 * std::hypot(a[k].stderr_mean(), b[k].stderr_mean()) + 0.01 * a[k].mean;
      EXPECT_NEAR(b[k].mean, a[k].mean, tol) << "channel " << k;
      // The march has far less noise than the path tracer.
      EXPECT_LT(b[k].stderr_mean(), a[k].stderr_mean());
    }
  }
}

}  // namespace
}  // namespace nimbus

namespace nimbus {
namespace {

double sphere_exit(const Vec3& p, const Vec3& w, double r) {
  const double b = dot(p, w), c = dot(p, p) - r * r;
  return -b + std::sqrt(std::max(0.0, b * b - c));
}

TEST(ShadowMap, MarchAndGridMatchAnalyticTransmittance) {
  const Scene scene = test::scene_from_json("{" + test::camera_json() + R"(,
    "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": [1.0, 2.0, 3.0]}],
    "lights": [{"type": "directional", "direction": [0.3, 1, -0.6], "irradiance": 1.0}]})");
  const SceneContext ctx(scene);
  const Vec3 to_light = -normalize(Vec3(0.3, 1, -0.6));
  const TransmittanceGrid map(ctx.media, ctx.majorants, scene.lights[0], 96, 0.05);
  Rng rng(5, 5);
  double worst_march = 0.0, sum_grid = 0.0, worst_grid = 0.0;
  const int n = 2000;
  for (int i = 0; i < n; ++i) {
    Vec3 p;
    do p = Vec3(2 * rng.uniform() - 1, 2 * rng.uniform() - 1, 2 * rng.uniform() - 1);
    while (p.length2() > 0.95);
    const double s = sphere_exit(p, to_light, 1.0);
    const Rgb exact(std::exp(-1.0 * s), std::exp(-2.0 * s), std::exp(-3.0 * s));
    const Rgb marched = marched_transmittance(ctx.media, ctx.majorants, p, to_light, 1e30, 0.05);
    const Rgb looked_up = map.lookup(p);
    for (int c = 0; c < 3; ++c) {
      worst_march = std::max(worst_march, std::abs(marched[c] - exact[c]));
      worst_grid = std::max(worst_grid, std::abs(looked_up[c] - exact[c]));
      sum_grid += std::abs(looked_up[c] - exact[c]);
    }
  }
  // The march only errs in the step that straddles the surface: at most tau_step of optical depth.
  EXPECT_LT(worst_march, 0.05);
  EXPECT_LT(sum_grid / (3 * n), 0.005);
  EXPECT_LT(worst_grid, 0.05);
}

TEST(Single, ShadowMapAgreesWithRatioTracking) {
  const Scene scene = test::scene_from_json("{" + test::camera_json() + R"(,
    "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": 2.0,
               "phase": {"type": "hg", "g": 0.5}}],
    "lights": [{"type": "directional", "direction": [0.5, 1, -0.3], "irradiance": 1.0}]})");
  const SceneContext ctx(scene);
  SingleSettings ratio{0.05, 1}, mapped{0.05, 1};
  mapped.transmittance = Transmittance::shadow_map;
  const SingleScatter a(ctx, ratio), b(ctx, mapped);
  test::MeanAccumulator ma, mb;
  for (int i = 0; i < 3000; ++i) {
    Rng r1(1, i), r2(2, i);
    ma.add(a.Li({Vec3(0, -4, 0), normalize(Vec3(0.1, 1, 0.1))}, r1)[0]);
    mb.add(b.Li({Vec3(0, -4, 0), normalize(Vec3(0.1, 1, 0.1))}, r2)[0]);
  }
  EXPECT_NEAR(mb.mean, ma.mean, 5 * std::hypot(ma.stderr_mean(), mb.stderr_mean()) + 0.01 * ma.mean);
}

}  // namespace
}  // namespace nimbus
