// The lidar into a scene's media (src/integrators/lidar_scene.h): a wide box reproduces the slab lidar
// (transport/lidar.h) within noise, Monte Carlo and single-scatter equation; two overlapping media with
// different phase functions against the single-scatter equation at small depth; causality; microscopic
// Beer-Lambert bin by bin; thread independence; bad settings.
#include "integrators/lidar_scene.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "media/phase.h"
#include "nimbus/error.h"
#include "nimbus/scene.h"
#include "support/scenes.h"

namespace nimbus {
namespace {

// A scene of the given media JSON (a light and a camera, which the lidar ignores).
Scene media_scene(const std::string& media) {
  const std::string text =
      "{" + test::camera_json() + R"(, "media": [)" + media +
      R"(], "lights": [{"type": "directional", "direction": [0, 0, -1], "irradiance": 1}]})";
  return parse_scene(nlohmann::json::parse(text), "lidar_test.json", ".");
}

std::string box(double z0, double z1, double sigma_s, double sigma_a, const std::string& phase) {
  return R"({"shape": {"type": "box", "min": [-60, -60, )" + std::to_string(z0) + "], \"max\": [60, 60, " +
         std::to_string(z1) + "]}, \"sigma_s\": " + std::to_string(sigma_s) +
         ", \"sigma_a\": " + std::to_string(sigma_a) + ", \"phase\": " + phase + "}";
}

LidarSettings slab_settings() {
  LidarSettings s;
  s.sigma_s = 1.0;
  s.sigma_a = 0.1;
  s.phase = HgPhase{0.7};
  s.thickness = 2.0;
  s.distance = 0.5;
  s.r_rx = 0.05;
  s.fov = 0.1;
  for (int i = 0; i <= 16; ++i) s.time_edges.push_back(1.0 + 0.25 * i);
  s.photons = 200000;
  s.seed = 3;
  return s;
}

SceneLidarSettings scene_settings(const LidarSettings& slab) {
  SceneLidarSettings s;
  s.n = slab.n;
  s.r_rx = slab.r_rx;
  s.fov = slab.fov;
  s.time_edges = slab.time_edges;
  s.photons = slab.photons;
  s.seed = slab.seed + 100;
  return s;
}

TEST(LidarScene, WideBoxIsTheSlab) {
  const LidarSettings slab = slab_settings();
  const SceneContext ctx(media_scene(box(0.5, 2.5, 1.0, 0.1, R"({"type": "hg", "g": 0.7})")));
  const SceneLidarSettings s = scene_settings(slab);
  const LidarMcResult a = run_lidar_mc(slab);
  const SceneLidarResult b = run_scene_lidar_mc(ctx, s);
  const std::vector<double> sa = lidar_single_scatter(slab), sb = scene_lidar_single_scatter(ctx, s);
  int powerful = 0;
  for (size_t i = 0; i < sa.size(); ++i) {
    const Estimate &x = a.received.bins[i], &y = b.received.bins[i];
    EXPECT_NEAR(x.value, y.value, 5.0 * std::hypot(x.err, y.err)) << i;
    powerful += y.err < 0.1 * y.value;
    EXPECT_NEAR(sb[i], sa[i], 1e-5 * sa[i]) << i;  // quadrature against the closed form
  }
  EXPECT_GE(powerful, 8);
  EXPECT_NEAR(a.total.value, b.total.value, 5.0 * std::hypot(a.total.err, b.total.err));
}

TEST(LidarScene, OverlappingMediaAgainstSingleScatterAtSmallDepth) {
  // Optical depth 0.3 in all; a point receiver with a narrow FOV sees almost only single scattering.
  const SceneContext ctx(media_scene(box(1.0, 3.0, 0.05, 0.01, R"({"type": "hg", "g": 0.5})") + "," +
                                     box(2.0, 4.0, 0.08, 0.0, R"({"type": "isotropic"})")));
  SceneLidarSettings s;
  s.fov = 0.002;
  for (int i = 0; i <= 10; ++i) s.time_edges.push_back(2.0 + 0.6 * i);  // ranges 1 .. 4
  s.photons = 200000;
  const SceneLidarResult mc = run_scene_lidar_mc(ctx, s);
  const std::vector<double> single = scene_lidar_single_scatter(ctx, s);
  int powerful = 0;
  for (size_t i = 0; i < single.size(); ++i) {
    const Estimate& m = mc.received.bins[i];
    EXPECT_NEAR(m.value, single[i], 5.0 * m.err + 0.01 * single[i]) << i;
    powerful += m.err < 0.05 * single[i];
  }
  EXPECT_GE(powerful, 8);
}

TEST(LidarScene, CausalAndBeerLambertBinByBin) {
  LidarSettings slab = slab_settings();
  slab.sigma_a = 0.0;
  SceneLidarSettings s = scene_settings(slab);
  s.n = 1.33;
  s.time_edges.clear();
  for (int i = 0; i <= 24; ++i) s.time_edges.push_back(0.25 * i);  // t = 0 .. 6
  const SceneContext clear(media_scene(box(0.5, 2.5, 1.0, 0.0, R"({"type": "hg", "g": 0.7})")));
  const SceneContext absorbing(media_scene(box(0.5, 2.5, 1.0, 0.3, R"({"type": "hg", "g": 0.7})")));
  const SceneLidarResult c = run_scene_lidar_mc(clear, s);
  s.seed += 1;
  const SceneLidarResult a = run_scene_lidar_mc(absorbing, s);
  int powerful = 0;
  for (size_t i = 0; i + 1 < s.time_edges.size(); ++i) {
    const double lo = s.time_edges[i], hi = s.time_edges[i + 1];
    if (hi <= 2.0 * s.n * 0.5) {  // before light can reach the box and come back
      EXPECT_EQ(c.received.bins[i].value, 0.0) << lo;
      continue;
    }
    if (lo < 2.0 * s.n * 0.5) continue;
    // Path inside the medium: t / n minus the gap out and back.
    const double w = std::exp(-0.3 * (0.5 * (lo + hi) / s.n - 1.0));
    const Estimate &x = c.received.bins[i], &y = a.received.bins[i];
    EXPECT_NEAR(y.value, w * x.value, 5.0 * std::hypot(y.err, w * x.err) + 3e-3 * y.value) << lo;
    powerful += y.err < 0.1 * y.value;
  }
  EXPECT_GE(powerful, 8);
}

TEST(LidarScene, SameForAnyNumberOfThreads) {
  const SceneContext ctx(media_scene(box(0.5, 2.5, 1.0, 0.1, R"({"type": "hg", "g": 0.7})")));
  SceneLidarSettings s = scene_settings(slab_settings());
  s.photons = 4000;
  const SceneLidarResult many = run_scene_lidar_mc(ctx, s);
  SceneLidarResult one;
  {
    tbb::global_control only(tbb::global_control::max_allowed_parallelism, 1);
    one = run_scene_lidar_mc(ctx, s);
  }
  for (size_t i = 0; i < many.received.bins.size(); ++i) {
    EXPECT_EQ(many.received.bins[i].value, one.received.bins[i].value);
    EXPECT_EQ(many.received.bins[i].err, one.received.bins[i].err);
  }
}

TEST(LidarScene, RejectsBadSettings) {
  const SceneContext ctx(media_scene(box(0.5, 2.5, 1.0, 0.1, R"({"type": "isotropic"})")));
  auto rejects = [&](auto change) {
    SceneLidarSettings s = scene_settings(slab_settings());
    change(s);
    EXPECT_THROW(run_scene_lidar_mc(ctx, s), Error);
    EXPECT_THROW(scene_lidar_single_scatter(ctx, s), Error);
  };
  rejects([](SceneLidarSettings& s) { s.dir = Vec3(0, 0, 2); });
  rejects([](SceneLidarSettings& s) { s.origin = Vec3(0, NAN, 0); });
  rejects([](SceneLidarSettings& s) { s.channel = 3; });
  rejects([](SceneLidarSettings& s) { s.fov = 0.0; });
  rejects([](SceneLidarSettings& s) { s.time_edges = {1.0, 0.5}; });
  rejects([](SceneLidarSettings& s) { s.n = 0.5; });
}

}  // namespace
}  // namespace nimbus
