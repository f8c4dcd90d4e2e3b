// The scatter grid's split of its photons among the lights (ScatterGridSettings::power_share): it
// changes which photons carry which light, never what the grid holds on average.
#include "integrators/scatter_grid.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <memory>

#include "support/scenes.h"
#include "transport/phase_split.h"

namespace nimbus {
namespace {

// A sphere lit by a sun and a sky (the sun ~89 % of the power towards it), or by the sun alone.
Scene split_scene(bool sky) {
  return test::scene_from_json("{" + test::camera_json(8, 8, 40.0) + R"(,
    "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": 4.0, "sigma_a": 0.1,
               "phase": {"type": "hg", "g": 0.8}}],
    "lights": [{"type": "directional", "direction": [-1, 0.3, 0.2], "irradiance": 3.0})" +
                               std::string(sky ? R"(, {"type": "environment", "radiance": 0.03})" : "") +
                               "]}");
}

// The grid's scattered light summed over fixed points and directions (an isotropic phase function's
// moments l <= 2, chi = 1, 0.5, 0.25) for photons split with power_share `share`, seed `seed`.
double grid_sum(const SceneContext& ctx, double share, uint64_t seed, int photons) {
  const Phase& phase = ctx.media.phase(0);
  const PhaseSplit split(phase, auto_peak_fraction(phase));
  ScatterGridSettings s;
  s.photons = photons;
  s.resolution = 12;
  s.power_share = share;
  s.seed = seed;
  const ScatterGrid grid(ctx, {&split}, {split.f()}, s);
  std::array<Rgb, kShMaxBands> chi;
  for (int l = 0; l < kShMaxBands; ++l) chi[l] = Rgb(std::pow(0.5, l));
  Rng rng(3, 0);
  double sum = 0.0;
  for (int i = 0; i < 64; ++i) {
    const Vec3 p(1.4 * rng.uniform() - 0.7, 1.4 * rng.uniform() - 0.7, 1.4 * rng.uniform() - 0.7);
    const Vec3 w = normalize(Vec3(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5));
    sum += luminance(grid.scattered(p, w, chi));
  }
  return sum;
}

// Photons shared evenly (0) or by power (1) give grids of the same mean over seeds, within their
// noise (a z-test of the difference of the means, 4 standard errors); and not the same grids.
TEST(ScatterGrid, PowerShareKeepsTheMean) {
  const Scene scene = split_scene(true);
  const SceneContext ctx(scene);
  constexpr int kSeeds = 8;
  double mean[2] = {}, var[2] = {};
  for (int k = 0; k < 2; ++k) {
    double v[kSeeds];
    for (int i = 0; i < kSeeds; ++i) v[i] = grid_sum(ctx, k == 0 ? 0.0 : 1.0, uint64_t(i + 1), 2048);
    for (double x : v) mean[k] += x / kSeeds;
    for (double x : v) var[k] += (x - mean[k]) * (x - mean[k]) / (kSeeds - 1);
  }
  const double se = std::sqrt((var[0] + var[1]) / kSeeds);
  std::printf("even %.5f +- %.5f, by power %.5f +- %.5f\n", mean[0], std::sqrt(var[0] / kSeeds), mean[1],
              std::sqrt(var[1] / kSeeds));
  ASSERT_GT(mean[0], 0.0);
  // The sun's photons carrying its power / (the even count) instead of / (its power share's count) would
  // put the sun's part of the grid ~80 % high (0.89 / 0.5), the sky's ~80 % low.
  EXPECT_LT(se, 0.05 * mean[0]);
  EXPECT_NEAR(mean[1], mean[0], 4.0 * se);
  EXPECT_NE(grid_sum(ctx, 0.0, 1, 4096), grid_sum(ctx, 1.0, 1, 4096));
}

// One source takes every photon whatever the share: the same grid.
TEST(ScatterGrid, PowerShareOfOneSource) {
  const Scene scene = split_scene(false);
  const SceneContext ctx(scene);
  EXPECT_EQ(grid_sum(ctx, 0.0, 7, 2048), grid_sum(ctx, 0.8, 7, 2048));
}

}  // namespace
}  // namespace nimbus
