// The scene lidar in the Disney cloud (src/integrators/lidar_scene.h; docs/validation/lidar.md): a ground
// lidar under the cloud base.  Nothing before the base; in the first bin of cloud, where it is thin, the
// Monte Carlo is the single-scatter equation; a few bins deeper, multiple scattering raises the return
// well above it.
#include <gtest/gtest.h>

#include <filesystem>

#include "integrators/lidar_scene.h"
#include "nimbus/scene.h"

namespace nimbus {
namespace {

TEST(LidarSceneSlow, DisneyCloudBaseIsSingleScatterThenMultipleScatteringTakesOver) {
  const std::filesystem::path file = std::filesystem::path(NIMBUS_SOURCE_DIR) / "scenes/disney_cloud.json";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << file;
  const Scene scene = load_scene(file);
  const SceneContext ctx(scene);
  SceneLidarSettings s;
  s.origin = Vec3(0.0, 70.0, -400.0);  // below the cloud; its base on this line is at range ~155
  s.r_rx = 0.5;
  s.fov = 0.01;
  for (int i = 0; i <= 5; ++i) s.time_edges.push_back(300.0 + 5.0 * i);
  s.photons = 300000;
  const SceneLidarResult mc = run_scene_lidar_mc(ctx, s);
  const std::vector<double> single = scene_lidar_single_scatter(ctx, s);
  EXPECT_EQ(mc.received.before.value, 0.0);
  EXPECT_EQ(mc.received.bins[0].value, 0.0);
  // t = 310-315: the thin cloud edge.
  const Estimate& edge = mc.received.bins[2];
  EXPECT_LT(edge.err, 0.03 * edge.value);
  EXPECT_NEAR(edge.value, single[2], 5.0 * edge.err + 0.01 * single[2]);
  // t = 320-325: the MC is far above single scattering (MC / single ~2.4 with 1e6 photons).
  const Estimate& deep = mc.received.bins[4];
  EXPECT_GT(deep.value - 5.0 * deep.err, 1.5 * single[4]);
}

}  // namespace
}  // namespace nimbus
