// TransmittanceGrid::build_pair (integrators/shadow_map.h): the full and the reduced map of a light from
// one march per node must equal the maps built alone, node for node (issue 12: the mfs set-up).
#include "integrators/shadow_map.h"

#include <gtest/gtest.h>

#include "core/rng.h"
#include "integrators/integrator.h"
#include "support/scenes.h"

namespace nimbus {
namespace {

// A thick chromatic sphere: the full optical depth across reaches ~100 (the march's stop at 50 is hit
// on the full map, not on the reduced one), lit by a directional and a point light.
TEST(ShadowMap, PairEqualsTheMapsBuiltAlone) {
  const Scene scene = test::scene_from_json("{" + test::camera_json(8, 8) + R"(,
    "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": [30, 40, 50],
               "sigma_a": [0.5, 1.0, 1.5], "phase": {"type": "hg", "g": 0.9}}],
    "lights": [{"type": "directional", "direction": [0.3, 1, -0.2], "irradiance": 2.0},
               {"type": "point", "position": [0.5, -1.8, 0.7], "intensity": 3.0}]})");
  const SceneContext ctx(scene);
  const std::vector<double> f = {0.81};
  Rng rng(7, 0);
  int deep = 0;
  for (const Light& light : ctx.lights) {
    const TransmittanceGrid full(ctx.media, ctx.majorants, light, 24, 0.25);
    const TransmittanceGrid reduced(ctx.media, ctx.majorants, light, 24, 0.25, f);
    TransmittanceGrid pair_full, pair_reduced;
    TransmittanceGrid::build_pair(ctx.media, ctx.majorants, light, 24, 0.25, f, &pair_full, &pair_reduced);
    for (int i = 0; i < 500; ++i) {
      const Vec3 p(2 * rng.uniform() - 1, 2 * rng.uniform() - 1, 2 * rng.uniform() - 1);
      const Rgb a = full.lookup(p), b = pair_full.lookup(p), c = reduced.lookup(p),
                d = pair_reduced.lookup(p);
      for (int k = 0; k < 3; ++k) {
        EXPECT_EQ(a[k], b[k]) << "full map at " << p;
        EXPECT_EQ(c[k], d[k]) << "reduced map at " << p;
        EXPECT_LE(a[k], c[k]);  // the reduced extinction lets more light through
      }
      deep += a[0] < 1e-12 && c[0] > 1e-12;
    }
  }
  EXPECT_GT(deep, 20);  // points where the full map is dark and the reduced one is not were tested
}

}  // namespace
}  // namespace nimbus
