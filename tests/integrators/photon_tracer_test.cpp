// The shared photon tracer of the scatter and beam grids: the batches and the work budget, the
// rejection sampler's explicit failure, and no failures in the grids `mfs` builds for a usual scene.
#include "integrators/photon_tracer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>

#include "integrators/mfs.h"
#include "support/scenes.h"

namespace nimbus {
namespace {

TEST(PhotonTracer, BatchesSumEveryPhotonOnce) {
  const size_t total = 1003;  // not a multiple of the batch count
  uint64_t failures = 0;
  const FloatArray sum = trace_photons(
      total, 42, 2, 0.5,
      [](size_t j, Rng& rng, PhotonBatch& batch) {
        batch.tally[0] += 1.0f;
        batch.tally[1] += float(j);
        batch.rejection_failures += j % 2;
      },
      &failures);
  EXPECT_FLOAT_EQ(sum[0], 0.5f * total);
  EXPECT_FLOAT_EQ(sum[1], 0.5f * total * (total - 1) / 2);
  EXPECT_EQ(failures, total / 2);
}

TEST(PhotonTracer, WorkBudgetScalesTheTracedPhotonsToThePlannedOnes) {
  const size_t total = kPhotonBatches * 10;
  std::atomic<size_t> traced{0};
  uint64_t failures = 0;
  // Each photon costs 4 times the budget's share: a batch of 10 stops after 3 photons (4 x 512 x 3 >
  // 512 x 10) and scales its tally by 10 / 3.
  const FloatArray sum = trace_photons(
      total, 1, 1, 1.0,
      [&](size_t, Rng&, PhotonBatch& batch) {
        batch.tally[0] += 1.0f;
        batch.collisions += 4.0 * kEventsPerPhoton;
        ++traced;
      },
      &failures);
  EXPECT_EQ(traced.load(), size_t(kPhotonBatches * 3));
  EXPECT_NEAR(sum[0], double(total), 1e-4);
}

// The walker's first flight through a constant-density sphere, over the shapes' pieces (the default for
// such media) and cell by cell of the majorant grid: the share of photons with a real collision is
// 1 - exp(-sigma 2 r) on a chord through the centre, and the mean distance to it is analytic, for real
// collisions at the full extinction (majorant scale 1) and at a third of it (scale 1/3, the beam grid's
// kind of density). Binomial and exponential standard errors, 4 of them.
TEST(PhotonTracer, FirstFlightThroughASphereIsExponential) {
  const Scene scene = test::scene_from_json("{" + test::camera_json(8, 8) + R"(,
    "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": 0.9, "sigma_a": 0.1}],
    "lights": [{"type": "directional", "direction": [1, 0, 0], "irradiance": 1.0}]})");
  const SceneContext pieces(scene);
  SceneContext cells(scene);
  ASSERT_TRUE(pieces.analytic.active());
  cells.analytic = AnalyticMedia();
  constexpr int kPhotons = 40000;
  for (const SceneContext* ctx : std::array<const SceneContext*, 2>{&pieces, &cells})
    for (const double share : {1.0, 1.0 / 3.0}) {
      const double sigma = 1.0 * share, chord = 2.0;
      int hits = 0;
      double depth = 0.0;
      double collisions = 0.0;
      for (int j = 0; j < kPhotons; ++j) {
        Rng rng(11, uint64_t(j));
        // Across the chord's length: the entry slightly off the axis (the sphere's chord is ~2 there).
        const Vec3 x(-3.0, 1e-3 * (rng.uniform() - 0.5), 0.0);
        double t_first = 0.0;
        bool hit = false;
        walk_photon(
            *ctx, ctx->majorants, x, Vec3(1, 0, 0), share, rng, &collisions,
            [&](const Vec3&) { return sigma; }, [&](const Vec3&, const Vec3&, double t) { t_first = t; },
            [&](const Vec3&, Vec3*) { return hit = true, false; },
            [](const SurfaceHit&, Vec3*) { return false; });
        if (hit) ++hits, depth += t_first - 2.0;  // the sphere starts 2 from x
      }
      const double p = 1.0 - std::exp(-sigma * chord);
      const double share_hit = double(hits) / kPhotons;
      EXPECT_NEAR(share_hit, p, 4.0 * std::sqrt(p * (1.0 - p) / kPhotons)) << "scale " << share;
      // The depth of a collision on the chord: an exponential truncated at the chord's length.
      const double e = std::exp(-sigma * chord);
      const double mean = (1.0 / sigma - e * (chord + 1.0 / sigma)) / (1.0 - e);
      const double m2 =
          (2.0 / (sigma * sigma) - e * (chord * chord + 2.0 * chord / sigma + 2.0 / (sigma * sigma))) /
          (1.0 - e);
      const double se = std::sqrt((m2 - mean * mean) / hits);
      EXPECT_NEAR(depth / hits, mean, 4.0 * se) << "scale " << share;
    }
}

TEST(PhotonTracer, RejectionFailureIsExplicitAndKeepsTheDirection) {
  int draws = 0;
  Vec3 w(0, 0, 1);
  const bool drawn = sample_by_rejection(
      &w, [&] { return ++draws, Vec3(1, 0, 0); }, [](const Vec3&) { return false; });
  EXPECT_FALSE(drawn);
  EXPECT_EQ(draws, kMaxRejectionTries);
  EXPECT_EQ(w, Vec3(0, 0, 1));
  draws = 0;
  EXPECT_TRUE(sample_by_rejection(
      &w, [&] { return Vec3(0, ++draws, 0); }, [&](const Vec3&) { return draws == 3; }));
  EXPECT_EQ(w, Vec3(0, 3, 0));
}

TEST(PhotonTracer, GridsOfAUsualSceneHaveNoRejectionFailures) {
  Scene scene = test::scene_from_json("{" + test::camera_json(8, 8) + R"(,
    "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": 4.0, "sigma_a": 0.05,
               "phase": {"type": "hg", "g": 0.8}}],
    "lights": [{"type": "directional", "direction": [-1, 0.3, 0.2], "irradiance": 1.0}]})");
  const SceneContext ctx(scene);
  const nlohmann::json options = {
      {"photon_transport", "similarity"}, {"photons", 1 << 14}, {"beam_photons", 1 << 12}};
  const MfsIntegrator mfs(ctx, mfs_settings_from_json(options, "test"));
  ASSERT_NE(mfs.scatter_grid(), nullptr);
  ASSERT_NE(mfs.beam_grid(), nullptr);
  EXPECT_EQ(mfs.scatter_grid()->rejection_failures(), 0u);
  EXPECT_EQ(mfs.beam_grid()->rejection_failures(), 0u);
}

// The footprint tests' scene: a unit sphere about (0.5, 0, 0) or a flat box, and one light (JSON), with the
// sphere about the media's bounding box (centre *c, radius *r) that ScatterGrid aims its photons at.
Scene footprint_scene(bool sphere, const std::string& light) {
  const std::string shape = sphere ? R"({"type": "sphere", "center": [0.5, 0, 0], "radius": 1})"
                                   : R"({"type": "box", "min": [-1, -0.5, -0.25], "max": [1, 0.5, 0.25]})";
  return test::scene_from_json("{" + test::camera_json(8, 8) + R"(, "media": [{"shape": )" + shape +
                               R"(, "sigma_s": 0.9, "sigma_a": 0.1}], "lights": [)" + light + "]}");
}
// Whether the footprint's raster cell that holds plane point (x, y) is one of its cells.
bool in_cells(const LightFootprint& fp, double x, double y) {
  const int u = int(std::floor((x + fp.half) / fp.cell)), v = int(std::floor((y + fp.half) / fp.cell));
  return std::binary_search(fp.cells.begin(), fp.cells.end(), uint32_t(v * fp.res + u));
}
void bounding_sphere(const SceneContext& ctx, Vec3* c, double* r) {
  const Bounds b = ctx.media.bounds();
  *c = (b.lo + b.hi) * 0.5;
  *r = 0.5 * (b.hi - b.lo).length() * (1.0 + 1e-9);
}

// A directional light's footprint (light_footprint) holds every line of emit's disc that meets a medium:
// lines through 200 000 uniform points of the disc, tested against the shape itself, for a sphere and for
// a box, lit obliquely. It is smaller than the disc (a sphere's: at most 0.9 of it, at least its own
// cross-section), and emit_over's photons start in it and carry E x area in all.
TEST(PhotonTracer, LightFootprintHoldsEveryLineThatMeetsTheMedia) {
  const Vec3 w = normalize(Vec3(1.0, 0.3, -0.2));
  for (const bool sphere : {true, false}) {
    const SceneContext ctx(
        footprint_scene(sphere, R"({"type": "directional", "direction": [1, 0, 0], "irradiance": 1.0})"));
    const Bounds b = ctx.media.bounds();
    Vec3 c;
    double r = 0.0;
    bounding_sphere(ctx, &c, &r);
    const std::optional<LightFootprint> fp = light_footprint(ctx.majorants, w, c, r);
    ASSERT_TRUE(fp.has_value()) << (sphere ? "sphere" : "box");
    const double disc = kPi * r * r;
    EXPECT_LT(fp->area(), 0.9 * disc);
    if (sphere) {
      EXPECT_GT(fp->area(), kPi);
    }
    const auto in_footprint = [&](double x, double y) { return in_cells(*fp, x, y); };
    int meeting = 0, missed = 0;
    Rng rng(5, 0);
    for (int j = 0; j < 200000; ++j) {
      const double rho = r * std::sqrt(rng.uniform()), phi = 2.0 * kPi * rng.uniform();
      const double x = rho * std::cos(phi), y = rho * std::sin(phi);
      const Vec3 o = fp->origin + fp->frame.to_world({x, y, 0.0});
      double t0 = 0.0, t1 = 0.0;
      const Vec3 oc = o - Vec3(0.5, 0, 0);
      const double along = -dot(oc, w);
      const bool meets = sphere ? (oc + w * along).length() < 1.0 : b.intersect(o, w, 0.0, 1e9, &t0, &t1);
      meeting += meets;
      missed += meets && !in_footprint(x, y);
    }
    EXPECT_GT(meeting, 10000);
    EXPECT_EQ(missed, 0) << (sphere ? "sphere" : "box");
    // emit_over: every photon starts on a footprint cell's line, along w, with power E area / n.
    const Rgb irradiance(2.0, 1.0, 0.5);
    for (int j = 0; j < 1000; ++j) {
      Rng prng(9, uint64_t(j));
      const Photon p = emit_over(*fp, irradiance, 1000.0, prng);
      const Vec3 q = fp->frame.to_local(p.x - fp->origin);
      EXPECT_NEAR(q.z, 0.0, 1e-9);
      EXPECT_TRUE(in_footprint(q.x, q.y));
      EXPECT_NEAR((p.w - w).length(), 0.0, 1e-12);
      EXPECT_NEAR(p.power.x * 1000.0, 2.0 * fp->area(), 1e-9 * fp->area());
    }
  }
}

// A point light's footprint (point_light_footprint) holds every direction from the light that meets the media
// (200 000 directions of the cone towards the media's sphere, tested against a sphere and a box), and
// emit_over's photons, whose power varies with their direction, carry the light's power into the sphere: the
// photons that hit it sum to I times its solid angle from the light, within 4 standard errors.
TEST(PhotonTracer, PointLightFootprintHoldsEveryLineThatMeetsTheMedia) {
  const Vec3 light(4.0, 1.5, -1.0), centre(0.5, 0, 0);
  for (const bool sphere : {true, false}) {
    const SceneContext ctx(
        footprint_scene(sphere, R"({"type": "point", "position": [4, 1.5, -1], "intensity": 1.0})"));
    const Bounds b = ctx.media.bounds();
    Vec3 c;
    double r = 0.0;
    bounding_sphere(ctx, &c, &r);
    const std::optional<LightFootprint> fp = point_light_footprint(ctx.majorants, light, c, r);
    ASSERT_TRUE(fp.has_value()) << (sphere ? "sphere" : "box");
    EXPECT_LT(fp->share, 0.9);
    const auto meets = [&](const Vec3& w) {
      double t0 = 0.0, t1 = 0.0;
      if (!sphere) return b.intersect(light, w, 0.0, 1e9, &t0, &t1);
      const Vec3 oc = light - centre;
      const double along = -dot(oc, w);
      return along > 0.0 && (oc + w * along).length() < 1.0;
    };
    const auto in_footprint = [&](const Vec3& w) {
      const Vec3 q = fp->frame.to_local(w);
      return in_cells(*fp, q.x * fp->dist / q.z, q.y * fp->dist / q.z);
    };
    const double dist = (c - light).length(), cos_max = std::sqrt(1.0 - r * r / (dist * dist));
    int meeting = 0, missed = 0;
    Rng rng(7, 0);
    for (int j = 0; j < 200000; ++j) {
      const Vec3 w = spherical_direction(1.0 - rng.uniform() * (1.0 - cos_max), 2.0 * kPi * rng.uniform(),
                                         (c - light) / dist);
      if (!meets(w)) continue;
      ++meeting;
      missed += !in_footprint(w);
    }
    EXPECT_GT(meeting, 10000);
    EXPECT_EQ(missed, 0) << (sphere ? "sphere" : "box");
    if (!sphere) continue;
    // The power into the unit sphere at distance d: I 2 pi (1 - sqrt(1 - 1 / d^2)).
    constexpr int kPhotons = 200000;
    double sum = 0.0, sum2 = 0.0;
    for (int j = 0; j < kPhotons; ++j) {
      Rng prng(9, uint64_t(j));
      const Photon p = emit_over(*fp, Rgb(1.0), double(kPhotons), prng);
      EXPECT_EQ(p.x, light);
      const double x = meets(p.w) ? p.power.x : 0.0;
      sum += x;
      sum2 += x * x;
    }
    const double d = (centre - light).length();
    const double expected = 2.0 * kPi * (1.0 - std::sqrt(1.0 - 1.0 / (d * d)));
    const double se = std::sqrt(std::max(0.0, sum2 - sum * sum / kPhotons));  // of the sum
    EXPECT_NEAR(sum, expected, 4.0 * se) << "se " << se;
    EXPECT_LT(se, 0.01 * expected);
  }
}

}  // namespace
}  // namespace nimbus
