// The scatter grid's hero-channel photons for chromatic media (ScatterGridSettings::channel_passes
// false) against one photon pass per channel: the same mean per channel (statistical, ~30 s).
#include <gtest/gtest.h>

#include <cstdio>
#include <memory>

#include "integrators/photon_tracer.h"
#include "integrators/scatter_grid.h"
#include "support/scenes.h"
#include "transport/phase_split.h"

namespace nimbus {
namespace {

// A chromatic sphere (scattering x [0.5, 1, 2], absorption the other way) in a second, grey-phase
// medium overlapping it, lit by a sun and a sky: the channels' extinctions differ 3.5x.
Scene chroma_scene() {
  return test::scene_from_json("{" + test::camera_json(8, 8, 40.0) + R"(,
    "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": [1.0, 2.0, 4.0],
               "sigma_a": [0.6, 0.3, 0.1], "phase": {"type": "hg", "g": 0.8}},
              {"shape": {"type": "box", "min": [-0.3, -1, -1], "max": [1.2, 1, 1]}, "sigma_s": [0.8, 0.4, 0.2],
               "phase": {"type": "hg", "g": 0.3}}],
    "lights": [{"type": "directional", "direction": [-1, 0.3, 0.2], "irradiance": 3.0},
               {"type": "environment", "radiance": [0.02, 0.03, 0.04]}]})");
}

// The chromatic scene's grid (hero-channel photons, or one pass per channel) summed per channel over
// fixed points and directions, as grid_sum.
Rgb chroma_sum(const SceneContext& ctx, bool channel_passes, bool exact, uint64_t seed, int photons) {
  std::vector<std::unique_ptr<PhaseSplit>> owned;
  std::vector<const PhaseSplit*> splits;
  std::vector<double> f;
  for (int i = 0; i < ctx.media.count(); ++i) {
    const Phase& phase = ctx.media.phase(i);
    owned.push_back(std::make_unique<PhaseSplit>(phase, auto_peak_fraction(phase)));
    splits.push_back(owned.back().get());
    f.push_back(owned.back()->f());
  }
  ScatterGridSettings s;
  s.photons = photons;
  s.resolution = 12;
  s.seed = seed;
  s.channel_passes = channel_passes;
  s.exact_transport = exact;
  const ScatterGrid grid(ctx, splits, f, s);
  std::array<Rgb, kShMaxBands> chi;
  for (int l = 0; l < kShMaxBands; ++l) chi[l] = Rgb(std::pow(0.5, l));
  Rng rng(5, 0);
  Rgb sum(0.0);
  for (int i = 0; i < 64; ++i) {
    const Vec3 p(1.6 * rng.uniform() - 0.8, 1.4 * rng.uniform() - 0.7, 1.4 * rng.uniform() - 0.7);
    const Vec3 w = normalize(Vec3(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5));
    sum += grid.scattered(p, w, chi);
  }
  return sum;
}

// Hero-channel photons (one pass, weighted per channel by the balance heuristic) and one pass per
// channel give grids of the same mean per channel over seeds, within their noise (a z-test of the
// difference of the means, 4 standard errors per channel), in the true medium and in the similarity
// one. Without the null collisions' weights (the walk.update of a null collision dropped) the
// true medium's channels are -17, -38 and +58 % off.
TEST(ScatterGrid, HeroChannelsKeepEachChannelsMean) {
  const Scene scene = chroma_scene();
  const SceneContext ctx(scene);
  ASSERT_FALSE(grey_media(ctx));
  constexpr int kSeeds = 16;
  for (const bool exact : {true, false}) {
    Rgb mean[2] = {Rgb(0.0), Rgb(0.0)}, var[2] = {Rgb(0.0), Rgb(0.0)};
    for (int k = 0; k < 2; ++k) {
      Rgb v[kSeeds];
      for (int i = 0; i < kSeeds; ++i) v[i] = chroma_sum(ctx, k == 1, exact, uint64_t(i + 1), 3000);
      for (const Rgb& x : v) mean[k] += x * (1.0 / kSeeds);
      for (const Rgb& x : v) var[k] += (x - mean[k]) * (x - mean[k]) * (1.0 / (kSeeds - 1));
    }
    for (int c = 0; c < 3; ++c) {
      const double se = std::sqrt((var[0][c] + var[1][c]) / kSeeds);
      std::printf("%s channel %d: hero %.5f +- %.5f, passes %.5f +- %.5f\n", exact ? "exact" : "similarity",
                  c, mean[0][c], std::sqrt(var[0][c] / kSeeds), mean[1][c], std::sqrt(var[1][c] / kSeeds));
      ASSERT_GT(mean[1][c], 0.0);
      EXPECT_LT(se, 0.04 * mean[1][c]);
      EXPECT_NEAR(mean[0][c], mean[1][c], 4.0 * se) << (exact ? "exact" : "similarity") << " channel " << c;
    }
  }
}

}  // namespace
}  // namespace nimbus
