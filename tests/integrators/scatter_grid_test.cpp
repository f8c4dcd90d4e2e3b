// The scatter grid's split of its photons among the lights (ScatterGridSettings::power_share): it
// changes which photons carry which light, never what the grid holds on average; and its deposits
// into the live nodes only (live_nodes_only), which change no node a lookup in the media reads; and the
// flights' deposit samples at random offsets (deposit_step), unbiased at any step.
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

// How grid_sum builds its grid and where it looks: at 64 fixed points of the cube [-0.7, 0.7]^3, or
// (shell) of the sphere's outer shell, radius 0.75 to 1, where flights cross its side.
struct SumOptions {
  Splat splat = Splat::trilinear;
  double deposit_step = 2.0;
  bool midpoints = false;
  bool shell = false;
  int points = 64;
};

// The grid's scattered light summed over fixed points and directions (an isotropic phase function's
// moments l <= 2, chi = 1, 0.5, 0.25) for photons split with power_share `share`, seed `seed`.
double grid_sum(const SceneContext& ctx, double share, uint64_t seed, int photons, const SumOptions& o = {}) {
  const Phase& phase = ctx.media.phase(0);
  const PhaseSplit split(phase, auto_peak_fraction(phase));
  ScatterGridSettings s;
  s.photons = photons;
  s.resolution = 12;
  s.power_share = share;
  s.seed = seed;
  s.splat = o.splat;
  s.deposit_step = o.deposit_step;
  s.deposit_midpoints = o.midpoints;
  const ScatterGrid grid(ctx, {&split}, {split.f()}, s);
  std::array<Rgb, kShMaxBands> chi;
  for (int l = 0; l < kShMaxBands; ++l) chi[l] = Rgb(std::pow(0.5, l));
  Rng rng(3, 0);
  double sum = 0.0;
  for (int i = 0; i < o.points; ++i) {
    Vec3 p(1.4 * rng.uniform() - 0.7, 1.4 * rng.uniform() - 0.7, 1.4 * rng.uniform() - 0.7);
    if (o.shell) p = normalize(p) * (0.75 + 0.25 * rng.uniform());
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
    for (int i = 0; i < kSeeds; ++i) v[i] = grid_sum(ctx, k == 0 ? 0.0 : 1.0, uint64_t(i + 1), 4096);
    for (double x : v) mean[k] += x / kSeeds;
    for (double x : v) var[k] += (x - mean[k]) * (x - mean[k]) / (kSeeds - 1);
  }
  const double se = std::sqrt((var[0] + var[1]) / kSeeds);
  std::printf("even %.5f +- %.5f, by power %.5f +- %.5f\n", mean[0], std::sqrt(var[0] / kSeeds), mean[1],
              std::sqrt(var[1] / kSeeds));
  ASSERT_GT(mean[0], 0.0);
  // The sun's photons carrying its power / (the even count) instead of / (its power share's count) would
  // put the sun's part of the grid ~80 % high (0.89 / 0.5), the sky's ~80 % low. (4096 photons per grid:
  // with 2048, clang's streams gave se = 5.03 % of the mean once the photons flew over the sphere's piece.)
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

// live_nodes_only: two spheres far apart, lit by a sun and a sky. The grid is the same, bit for bit,
// wherever a medium is (the same photons, the same sums at every node a lookup there reads), and empty
// in the gap between them, which the full grid's photons cross.
TEST(ScatterGrid, LiveNodesOnlyKeepTheMediaBitForBit) {
  const Scene scene = test::scene_from_json("{" + test::camera_json(8, 8, 40.0) + R"(,
    "media": [{"shape": {"type": "sphere", "center": [-2, 0, 0], "radius": 0.6}, "sigma_s": 4.0, "sigma_a": 0.1,
               "phase": {"type": "hg", "g": 0.8}},
              {"shape": {"type": "sphere", "center": [2, 0, 0], "radius": 0.6}, "sigma_s": 2.0, "sigma_a": 0.1,
               "phase": {"type": "hg", "g": 0.5}}],
    "lights": [{"type": "directional", "direction": [-1, 0.3, 0.2], "irradiance": 3.0},
               {"type": "environment", "radiance": 0.1}]})");
  const SceneContext ctx(scene);
  std::vector<std::unique_ptr<PhaseSplit>> owned;
  std::vector<const PhaseSplit*> splits;
  std::vector<double> f;
  for (int i = 0; i < 2; ++i) {
    const Phase& phase = ctx.media.phase(i);
    owned.push_back(std::make_unique<PhaseSplit>(phase, auto_peak_fraction(phase)));
    splits.push_back(owned.back().get());
    f.push_back(owned.back()->f());
  }
  ScatterGridSettings s;
  s.photons = 4096;
  s.resolution = 24;
  const ScatterGrid full(ctx, splits, f, s);
  s.live_nodes_only = true;
  const ScatterGrid live(ctx, splits, f, s);
  std::array<Rgb, kShMaxBands> chi;
  for (int l = 0; l < kShMaxBands; ++l) chi[l] = Rgb(std::pow(0.5, l));
  Rng rng(11, 0);
  int inside = 0, lit = 0;
  for (int i = 0; i < 4000; ++i) {
    const Vec3 p(6.0 * rng.uniform() - 3.0, 1.4 * rng.uniform() - 0.7, 1.4 * rng.uniform() - 0.7);
    const Vec3 w = normalize(Vec3(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5));
    const Rgb a = full.scattered(p, w, chi), b = live.scattered(p, w, chi);
    if (max_component(ctx.media.sigma_t(p)) > 0.0) {
      ++inside;
      lit += a[0] > 0.0;
      for (int c = 0; c < 3; ++c) ASSERT_EQ(a[c], b[c]) << p.x << " " << p.y << " " << p.z;
    }
  }
  EXPECT_GT(inside, 200);
  EXPECT_GT(lit, inside / 2);
  const Rgb gap_full = full.scattered(Vec3(0, 0, 0), Vec3(0, 0, 1), chi),
            gap_live = live.scattered(Vec3(0, 0, 0), Vec3(0, 0, 1), chi);
  EXPECT_GT(gap_full[0], 0.0);
  EXPECT_EQ(gap_live[0], 0.0);
}

// With K = 1 (max_wide_scatters 1) the grid holds the environment's light only (the lights' first wide scatter
// is the camera march's): a sun beside the sky changes nothing, bit for bit. (The sun's footprint once stood
// for the sky's photons there: its light entered the grid from its entry.)
TEST(ScatterGrid, FirstOrderOnlyHoldsTheEnvironmentAlone) {
  const auto grid_of = [](bool sun) {
    const Scene scene = test::scene_from_json(
        "{" + test::camera_json(8, 8, 40.0) + R"(,
      "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": 4.0, "sigma_a": 0.1,
                 "phase": {"type": "hg", "g": 0.8}}],
      "lights": [)" +
        std::string(sun ? R"({"type": "directional", "direction": [-1, 0.3, 0.2], "irradiance": 3.0},)"
                        : "") +
        R"({"type": "environment", "radiance": 0.1}]})");
    const SceneContext ctx(scene);
    const Phase& phase = ctx.media.phase(0);
    const PhaseSplit split(phase, auto_peak_fraction(phase));
    ScatterGridSettings s;
    s.photons = 4096;
    s.resolution = 12;
    s.max_wide_scatters = 1;
    const ScatterGrid grid(ctx, {&split}, {split.f()}, s);
    std::array<Rgb, kShMaxBands> chi;
    for (int l = 0; l < kShMaxBands; ++l) chi[l] = Rgb(std::pow(0.5, l));
    std::vector<double> v;
    Rng rng(5, 0);
    for (int i = 0; i < 200; ++i) {
      const Vec3 p(1.4 * rng.uniform() - 0.7, 1.4 * rng.uniform() - 0.7, 1.4 * rng.uniform() - 0.7);
      const Vec3 w = normalize(Vec3(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5));
      v.push_back(luminance(grid.scattered(p, w, chi)));
    }
    return v;
  };
  const std::vector<double> sky = grid_of(false), both = grid_of(true);
  double sum = 0.0;
  for (size_t i = 0; i < sky.size(); ++i) {
    ASSERT_EQ(both[i], sky[i]) << i;
    sum += sky[i];
  }
  EXPECT_GT(sum, 0.0);
}

// The stochastic splats (one node per deposit sample, drawn by its trilinear weight) keep the grid's
// mean: the same photons (the same seed: the walks do not depend on the splat) deposited trilinearly and
// stochastically, over seeds; the paired differences' mean is 0 within 4 of its standard errors. And
// the grids differ (the splat noise is there), by more than rounding.
TEST(ScatterGrid, StochasticSplatKeepsTheMean) {
  const Scene scene = split_scene(true);
  const SceneContext ctx(scene);
  constexpr int kSeeds = 12;
  for (Splat splat : {Splat::stochastic, Splat::stratified}) {
    double mean = 0.0, sq = 0.0, base = 0.0;
    for (int k = 0; k < kSeeds; ++k) {
      const double tri = grid_sum(ctx, 0.8, 100 + k, 2048);
      const double d = grid_sum(ctx, 0.8, 100 + k, 2048, {.splat = splat}) - tri;
      mean += d / kSeeds;
      sq += d * d;
      base += tri / kSeeds;
    }
    const double se = std::sqrt(std::max(0.0, sq / kSeeds - mean * mean) / (kSeeds - 1));
    std::printf("splat %d: trilinear %.5f, stochastic - trilinear %.5f +- %.5f\n", int(splat), base, mean,
                se);
    ASSERT_GT(base, 0.0);
    EXPECT_GT(se, 1e-5 * base);  // the splat's own noise
    EXPECT_LT(se, 0.05 * base);
    EXPECT_NEAR(mean, 0.0, 4.0 * se);
  }
}

// A flight's deposit samples at a random offset within each part of it (deposit_step spacings at most)
// are unbiased at any step: the grid at 4 spacings against the same photons' grid at a quarter spacing
// (one offset drawn per flight either way, so the walks are the same and the difference is the
// deposits' alone), summed over 512 points of the sphere's outer shell and paired by seed, differ by less
// than 4 standard errors of the mean difference. At the parts' midpoints (deposit_midpoints) a flight
// that crosses the sphere's side leaves the wrong share inside: the same comparison shows their bias,
// about -4 % (the test could fail).
TEST(ScatterGrid, JitteredDepositsKeepTheTrackLengthIntegral) {
  const Scene scene = split_scene(false);
  const SceneContext ctx(scene);
  constexpr int kSeeds = 12;
  for (bool mid : {false, true}) {
    double mean = 0.0, sq = 0.0, fine = 0.0;
    for (int k = 0; k < kSeeds; ++k) {
      const double f = grid_sum(ctx, 0.8, 200 + k, 2048,
                                {.deposit_step = 0.25, .midpoints = mid, .shell = true, .points = 512});
      const double d = grid_sum(ctx, 0.8, 200 + k, 2048,
                                {.deposit_step = 4.0, .midpoints = mid, .shell = true, .points = 512}) -
                       f;
      mean += d / kSeeds;
      sq += d * d;
      fine += f / kSeeds;
    }
    const double se = std::sqrt(std::max(0.0, sq / kSeeds - mean * mean) / (kSeeds - 1));
    std::printf("midpoints %d: quarter spacing %.5f, 4 spacings - quarter %.5f +- %.5f\n", int(mid), fine,
                mean, se);
    ASSERT_GT(fine, 0.0);
    EXPECT_LT(se, 0.05 * fine);
    if (mid)
      EXPECT_GT(std::abs(mean), 4.0 * se);
    else
      EXPECT_NEAR(mean, 0.0, 4.0 * se);
  }
}

// On constant-density shapes the photons fly over the shapes' exact pieces (one exponential step per
// collision) instead of cell by cell of the majorant grid: the same walks in distribution, so grids of
// the same mean over seeds within their noise (a z-test of the difference, 4 standard errors), and not
// the same grids (the other path was taken). The same for a box lit from the side, a sphere with a
// sky (photons entering from every side) and a lone pure absorber under a sky (whose pieces' majorant is
// twice its extinction: AnalyticMedia; the sky's flights are deposited from their entry).
TEST(ScatterGrid, PhotonsOverAnalyticPiecesKeepTheMean) {
  const Scene sphere = split_scene(true);
  const Scene box = test::scene_from_json("{" + test::camera_json(8, 8, 40.0) + R"(,
    "media": [{"shape": {"type": "box", "min": [-0.7, -0.6, -0.8], "max": [0.7, 0.6, 0.8]}, "sigma_s": 6.0,
               "sigma_a": 0.05, "phase": {"type": "hg", "g": 0.85}}],
    "lights": [{"type": "directional", "direction": [-1, 0.3, 0.2], "irradiance": 3.0}]})");
  const Scene absorber = test::scene_from_json("{" + test::camera_json(8, 8, 40.0) + R"(,
    "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": 0.0, "sigma_a": 2.0}],
    "lights": [{"type": "environment", "radiance": 0.5}]})");
  for (const Scene* scene : {&sphere, &box, &absorber}) {
    const SceneContext pieces(*scene);
    SceneContext cells(*scene);
    ASSERT_TRUE(pieces.analytic.active());
    cells.analytic = AnalyticMedia();  // the majorant grid's cells
    constexpr int kSeeds = 12;
    double mean[2] = {}, var[2] = {};
    for (int k = 0; k < 2; ++k) {
      double v[kSeeds];
      for (int i = 0; i < kSeeds; ++i) v[i] = grid_sum(k == 0 ? pieces : cells, 1.0, uint64_t(i + 1), 2048);
      for (double x : v) mean[k] += x / kSeeds;
      for (double x : v) var[k] += (x - mean[k]) * (x - mean[k]) / (kSeeds - 1);
    }
    const double se = std::sqrt((var[0] + var[1]) / kSeeds);
    std::printf("pieces %.5f +- %.5f, cells %.5f +- %.5f\n", mean[0], std::sqrt(var[0] / kSeeds), mean[1],
                std::sqrt(var[1] / kSeeds));
    ASSERT_GT(mean[0], 0.0);
    EXPECT_LT(se, 0.05 * mean[0]);
    EXPECT_NEAR(mean[0], mean[1], 4.0 * se);
    EXPECT_NE(grid_sum(pieces, 1.0, 1, 2048), grid_sum(cells, 1.0, 1, 2048));
  }
}

// Grey media lit by sources of one colour keep one channel per node (the moments in units of the
// colour, which the lookup multiplies back in): a sun of colour (1, 0.5, 0.25) gives, channel by
// channel, that colour times the grid of a white sun of the same strength (the same photons: the
// strongest channel sets their power), in a third of the memory of a grid whose sun and sky differ in
// colour.
TEST(ScatterGrid, OneColourOfLightKeepsOneChannel) {
  const auto grid_of = [](const std::string& lights) {
    return test::scene_from_json("{" + test::camera_json(8, 8, 40.0) + R"(,
      "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": 4.0, "sigma_a": 0.1,
                 "phase": {"type": "hg", "g": 0.8}}], "lights": [)" +
                                 lights + "]}");
  };
  const Scene white = grid_of(R"({"type": "directional", "direction": [-1, 0.3, 0.2], "irradiance": 3.0})");
  const Scene tinted =
      grid_of(R"({"type": "directional", "direction": [-1, 0.3, 0.2], "irradiance": [3.0, 1.5, 0.75]})");
  const Scene mixed =
      grid_of(R"({"type": "directional", "direction": [-1, 0.3, 0.2], "irradiance": [3.0, 1.5, 0.75]},
                                 {"type": "environment", "radiance": 0.03})");
  std::vector<std::unique_ptr<SceneContext>> ctx;
  std::vector<std::unique_ptr<ScatterGrid>> grids;
  const Phase& phase = white.media.front().phase;
  const PhaseSplit split(phase, auto_peak_fraction(phase));
  ScatterGridSettings s;
  s.photons = 2048;
  s.resolution = 12;
  s.prefiltered = false;
  for (const Scene* scene : {&white, &tinted, &mixed}) {
    ctx.push_back(std::make_unique<SceneContext>(*scene));
    grids.push_back(std::make_unique<ScatterGrid>(*ctx.back(), std::vector<const PhaseSplit*>{&split},
                                                  std::vector<double>{split.f()}, s));
  }
  EXPECT_EQ(3 * grids[0]->memory_bytes(), grids[2]->memory_bytes());
  EXPECT_EQ(grids[0]->memory_bytes(), grids[1]->memory_bytes());
  std::array<Rgb, kShMaxBands> chi;
  for (int l = 0; l < kShMaxBands; ++l) chi[l] = Rgb(std::pow(0.5, l), std::pow(0.6, l), std::pow(0.7, l));
  const Rgb tint(1.0, 0.5, 0.25);
  Rng rng(5, 0);
  int lit = 0;
  for (int i = 0; i < 200; ++i) {
    const Vec3 p(1.4 * rng.uniform() - 0.7, 1.4 * rng.uniform() - 0.7, 1.4 * rng.uniform() - 0.7);
    const Vec3 w = normalize(Vec3(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5));
    const Rgb a = grids[0]->scattered(p, w, chi), b = grids[1]->scattered(p, w, chi);
    lit += a[0] > 0.0;
    for (int c = 0; c < 3; ++c) ASSERT_EQ(b[c], tint[c] * a[c]) << i << " " << c;
  }
  EXPECT_GT(lit, 100);
}

// The photon count's pilot (adaptive_photons) counts the tracking's work, null collisions with the real ones:
// a thin sphere's photons tracked over its exact piece meet real collisions only; over a majorant grid of
// 2 x 2 x 2 cells, whose majorant fills the sphere's bounding cube, they meet about as many null ones in the
// cube's corners (the cube holds 1.9 x the sphere's volume) for the same real ones. So the pilot counts more
// collisions per photon there and the grid traces fewer photons.
TEST(ScatterGrid, PilotCountsNullCollisionsAsWork) {
  const Scene scene = test::scene_from_json("{" + test::camera_json(8, 8, 40.0) + R"(,
    "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": 0.3, "sigma_a": 0.01,
               "phase": {"type": "hg", "g": 0.8}}],
    "lights": [{"type": "directional", "direction": [-1, 0.3, 0.2], "irradiance": 3.0}]})");
  const SceneContext pieces(scene);
  SceneContext cells(scene);
  cells.analytic = AnalyticMedia();
  cells.majorants = MajorantGrid(cells.media, 2);
  const Phase& phase = scene.media.front().phase;
  const PhaseSplit split(phase, auto_peak_fraction(phase));
  ScatterGridSettings s;
  s.photons = s.adaptive_photons = 4096;
  s.resolution = 8;
  const ScatterGrid a(pieces, {&split}, {split.f()}, s), b(cells, {&split}, {split.f()}, s);
  ASSERT_TRUE(a.collisions_per_photon() && b.collisions_per_photon());
  std::printf("collisions per photon: pieces %.3f, cells %.3f; photons %d, %d\n", *a.collisions_per_photon(),
              *b.collisions_per_photon(), a.photons(), b.photons());
  EXPECT_GT(*b.collisions_per_photon(), 1.4 * *a.collisions_per_photon());
  EXPECT_LT(b.photons(), a.photons());
}

}  // namespace
}  // namespace nimbus
