// `single` against the reference restricted to one scattering event (pathtrace, max_events = 1).
#include <gtest/gtest.h>

#include "integrators/pathtrace.h"
#include "integrators/single.h"
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
      const Rgb la = pt.radiance(Vec3(0, -4, 0), d, r1), lb = single.radiance(Vec3(0, -4, 0), d, r2);
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
