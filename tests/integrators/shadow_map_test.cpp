// TransmittanceGrid (integrators/shadow_map.h): the full and the reduced map of a light from one walk
// must equal the maps built alone, node for node, by the march and by the sweep; the swept map against
// the per-node march and against Beer-Lambert's closed form (issue 12: the mfs set-up).
#include "integrators/shadow_map.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/node_grid.h"
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
  for (const MapBuild how : {MapBuild{.sweep = false}, MapBuild{}})
    for (const Light& light : ctx.lights) {
      const TransmittanceGrid full(ctx.media, ctx.majorants, light, 24, 0.25, {}, how);
      const TransmittanceGrid reduced(ctx.media, ctx.majorants, light, 24, 0.25, f, how);
      TransmittanceGrid pair_full, pair_reduced;
      TransmittanceGrid::build_pair(ctx.media, ctx.majorants, light, 24, 0.25, f, &pair_full, &pair_reduced,
                                    how);
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
  EXPECT_GT(deep, 40);  // points where the full map is dark and the reduced one is not were tested
}

// The density-weighted RMS and mean of (a - b) over the nodes of a `resolution` map (green channel).
struct MapDifference {
  double rms = 0.0, mean = 0.0;
};
MapDifference sweep_difference(const SceneContext& ctx, int resolution, const TransmittanceGrid& a,
                               const TransmittanceGrid& b) {
  const NodeGrid g = node_grid_spanning(ctx.majorants.bounds(), resolution);
  double W = 0.0, s2 = 0.0, s1 = 0.0;
  for (int z = 0; z < g.nodes[2]; ++z)
    for (int y = 0; y < g.nodes[1]; ++y)
      for (int x = 0; x < g.nodes[0]; ++x) {
        const Vec3 p = g.position(x, y, z);
        const double w = ctx.media.sigma_t(p)[1], d = a.lookup(p)[1] - b.lookup(p)[1];
        W += w, s2 += w * d * d, s1 += w * d;
      }
  return {std::sqrt(s2 / W), s1 / W};
}

// The swept maps (full and reduced) against the per-node march at two resolutions: a heterogeneous
// cloud and a homogeneous sphere, lit along no axis (every sweep step interpolates across both axes).
// The sweep's own error is the interpolation in the slices (O(h^2) per step, N / stride steps), so
// its distance from the march must shrink as the resolution doubles.
TEST(ShadowMap, SweepAgreesWithTheMarch) {
  const std::string lights =
      R"("lights": [{"type": "directional", "direction": [-0.75, -0.3, -0.55], "irradiance": 2.0}])";
  const std::string media[] = {
      R"({"shape": {"type": "cloud", "radius": 0.9, "seed": 5, "resolution": 48}, "sigma_s": 8})",
      R"({"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": 2})"};
  const std::vector<double> f = {0.8};
  for (const std::string& medium : media) {
    const Scene scene = test::scene_from_json("{" + test::camera_json(8, 8) + R"(, "media": [)" + medium +
                                              "], " + lights + "}");
    const SceneContext ctx(scene);
    MapDifference d[2][2];  // [resolution][full, reduced]
    for (int r = 0; r < 2; ++r) {
      const int res = r ? 48 : 24;
      TransmittanceGrid march_full, march_reduced, sweep_full, sweep_reduced;
      TransmittanceGrid::build_pair(ctx.media, ctx.majorants, ctx.lights[0], res, 0.05, f, &march_full,
                                    &march_reduced, MapBuild{.sweep = false});
      TransmittanceGrid::build_pair(ctx.media, ctx.majorants, ctx.lights[0], res, 0.05, f, &sweep_full,
                                    &sweep_reduced);
      d[r][0] = sweep_difference(ctx, res, sweep_full, march_full);
      d[r][1] = sweep_difference(ctx, res, sweep_reduced, march_reduced);
    }
    // Measured (cloud; sphere): rms 0.0072, 0.0058 at 24 nodes -> 0.0033, 0.0025 at 48 (full, reduced);
    // 0.0080, 0.0028 -> 0.0064, 0.0022 (the sphere's surface, where T has a kink, converges slowest);
    // weighted means within 0.0006. A bilinear sweep at one slice per step is 2-3x further off.
    for (int m = 0; m < 2; ++m) {
      EXPECT_LT(d[1][m].rms, 0.9 * d[0][m].rms) << medium << (m ? " reduced" : " full");
      EXPECT_LT(d[1][m].rms, 0.01) << medium << (m ? " reduced" : " full");
      for (int r = 0; r < 2; ++r) EXPECT_LT(std::abs(d[r][m].mean), 0.002) << medium;
    }
  }
}

// The analytic case: a homogeneous sphere, T(p) = exp(-sigma_t t(p)) with t(p) the distance from p to
// the sphere's surface towards the light; the swept map at the nodes inside the sphere.
TEST(ShadowMap, SweptSphereIsBeerLambert) {
  const double sigma = 2.0;
  const Vec3 w = normalize(Vec3(0.75, 0.3, 0.55));  // towards the light
  const Scene scene = test::scene_from_json("{" + test::camera_json(8, 8) + R"(,
    "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": 2}],
    "lights": [{"type": "directional", "direction": [-0.75, -0.3, -0.55], "irradiance": 2.0}]})");
  const SceneContext ctx(scene);
  for (int res : {24, 48}) {
    TransmittanceGrid swept(ctx.media, ctx.majorants, ctx.lights[0], res, 0.01);
    TransmittanceGrid marched(ctx.media, ctx.majorants, ctx.lights[0], res, 0.01, {},
                              MapBuild{.sweep = false});
    const NodeGrid g = node_grid_spanning(ctx.majorants.bounds(), res);
    double s2 = 0.0, m2 = 0.0, worst = 0.0;
    int n = 0;
    for (int z = 0; z < g.nodes[2]; ++z)
      for (int y = 0; y < g.nodes[1]; ++y)
        for (int x = 0; x < g.nodes[0]; ++x) {
          const Vec3 p = g.position(x, y, z);
          if (length(p) > 0.9) continue;
          const double b = dot(p, w), t = -b + std::sqrt(b * b - dot(p, p) + 1.0);
          const double exact = std::exp(-sigma * t);
          const double e = swept.lookup(p)[0] / exact - 1.0, m = marched.lookup(p)[0] / exact - 1.0;
          s2 += e * e, m2 += m * m, worst = std::max(worst, std::abs(e)), ++n;
        }
    // Measured: relative rms 0.0074 at 24 nodes, 0.0027 at 48 (the march: 0.0027 at both, its midpoint
    // rule at the surface); the worst node 0.048 and 0.022 (grazing the light-side surface).
    const double rms = std::sqrt(s2 / n);
    EXPECT_LT(rms, res == 24 ? 0.012 : 0.005) << res;
    EXPECT_LT(worst, res == 24 ? 0.08 : 0.04) << res;
    EXPECT_LT(std::sqrt(m2 / n), 0.005) << res;
  }
}

}  // namespace
}  // namespace nimbus
