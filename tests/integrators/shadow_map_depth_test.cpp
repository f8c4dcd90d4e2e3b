// TransmittanceGrid::lookup interpolates optical depth, not transmittance (integrators/shadow_map.h):
// where the depth along the light's path is linear in position (a homogeneous box lit along an axis)
// the map is exact between its nodes, where a lerp of T would be too bright by the convexity of exp
// (~5 % half-way between nodes here).
#include <gtest/gtest.h>

#include <cmath>

#include "core/rng.h"
#include "integrators/integrator.h"
#include "integrators/shadow_map.h"
#include "support/scenes.h"

namespace nimbus {
namespace {

TEST(ShadowMapDepth, BetweenNodesAHomogeneousBoxIsExact) {
  constexpr double kSigma = 5.0;  // sigma_t: 10 optical depths across the box, 0.67 between nodes
  const Scene scene = test::scene_from_json("{" + test::camera_json(8, 8) + R"(,
    "media": [{"shape": {"type": "box", "min": [-1, -1, -1], "max": [1, 1, 1]}, "sigma_s": 4.0,
               "sigma_a": 1.0, "phase": {"type": "hg", "g": 0.5}}],
    "lights": [{"type": "directional", "direction": [0, 0, -1], "irradiance": 1.0}]})");
  const SceneContext ctx(scene);
  const TransmittanceGrid map(ctx.media, ctx.majorants, ctx.lights[0], 16, 0.25);
  Rng rng(11, 0);
  double worst = 0.0, lerp_worst = 0.0;
  for (int i = 0; i < 400; ++i) {
    // Away from the side faces (within a node spacing of them the map mixes nodes outside the box,
    // which the light reaches unattenuated).
    const double x = 1.5 * rng.uniform() - 0.75, y = 1.5 * rng.uniform() - 0.75,
                 z = 1.8 * rng.uniform() - 0.9;
    const Vec3 p(x, y, z);
    // The light travels along -z: it enters at the top face z = 1.
    const double exact = std::exp(-kSigma * (1.0 - p.z));
    worst = std::max(worst, std::abs(map.lookup(p)[0] / exact - 1.0));
    // What a lerp of the nodes' T would give along z (nodes 2 / 15 apart, on the faces).
    const double h = 2.0 / 15.0, u = (p.z + 1.0) / h, f = u - std::floor(u);
    const double z0 = -1.0 + std::floor(u) * h;
    const double lerp = (1 - f) * std::exp(-kSigma * (1.0 - z0)) + f * std::exp(-kSigma * (1.0 - z0 - h));
    lerp_worst = std::max(lerp_worst, lerp / exact - 1.0);
  }
  EXPECT_LT(worst, 1e-4);       // float depths: exact up to rounding
  EXPECT_GT(lerp_worst, 0.03);  // the check can tell: interpolating T would be off by this much
}

}  // namespace
}  // namespace nimbus
