// Volumes in scenes: the shared files load through the scene parser, errors name scene, field and
// volume file, and the majorant grid over a real cloud is conservative and unbiased.
#include <gtest/gtest.h>

#include <filesystem>

#include "integrators/pathtrace.h"
#include "io/vdb.h"
#include "nimbus/error.h"
#include "support/scenes.h"
#include "support/stats.h"

namespace nimbus {
namespace {

const std::filesystem::path kShared = NIMBUS_SHARED_DIR;

std::string cloud_scene(const std::string& file, const std::string& grid = "density") {
  return "{" + test::camera_json(8, 8, 35, 900) + R"(,
    "media": [{"shape": {"type": "vdb", "file": ")" +
         file + R"(", "grid": ")" + grid + R"(", "scale": 1.0},
               "sigma_s": 0.1, "sigma_a": 0.001, "phase": {"type": "hg", "g": 0.8}}],
    "lights": [{"type": "directional", "direction": [-0.5, 0.6, -0.62], "irradiance": 3.0},
               {"type": "environment", "radiance": [0.06, 0.1, 0.2]}]})";
}

TEST(SceneVdb, ErrorsNameSceneFieldAndFile) {
  try {
    test::scene_from_json(cloud_scene("/nonexistent/cloud.vdb"));
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("test.json: /media/0/shape/file: /nonexistent/cloud.vdb", 0), 0u)
        << e.what();
  }
  const auto cloud = kShared / "data/volumes/wdas_cloud_sixteenth.vdb";
  if (!std::filesystem::exists(cloud)) GTEST_SKIP();
  try {
    test::scene_from_json(cloud_scene(cloud.string(), "temperature"));
    FAIL();
  } catch (const Error& e) {
    const std::string msg = e.what();
    EXPECT_EQ(msg.rfind("test.json: /media/0/shape/file: ", 0), 0u) << msg;
    EXPECT_NE(msg.find("temperature"), std::string::npos) << msg;
    EXPECT_NE(msg.find("density"), std::string::npos) << msg;  // lists what is there
  }
}

// On the Disney cloud, delta tracking against the majorant grid and against one global majorant
// give the same radiance (the grid is conservative: a violated majorant would bias it).
TEST(SceneVdb, MajorantGridIsUnbiasedOnTheDisneyCloud) {
  const auto cloud = kShared / "data/volumes/wdas_cloud_sixteenth.vdb";
  if (!std::filesystem::exists(cloud)) GTEST_SKIP();
  const Scene scene = test::scene_from_json(cloud_scene(cloud.string()));
  const SceneContext grid_ctx(scene), global_ctx(scene, 0, true);
  const auto res = grid_ctx.majorants.resolution();
  EXPECT_GT(res[0] * res[1] * res[2], 1000);
  const PathTracer a(grid_ctx, 0), b(global_ctx, 0);
  const Vec3 o(0, -900, 40);
  for (const Vec3& target : {Vec3(0, 0, 40), Vec3(60, 0, 80), Vec3(-80, 0, 10)}) {
    const Vec3 d = normalize(target - o);
    test::MeanAccumulator ma, mb;
    for (int i = 0; i < 4000; ++i) {
      Rng r1(1, i), r2(2, i);
      ma.add(luminance(a.Li({o, d}, r1)));
      mb.add(luminance(b.Li({o, d}, r2)));
    }
    EXPECT_NEAR(ma.mean, mb.mean, 5 * std::hypot(ma.stderr_mean(), mb.stderr_mean()));
  }
}

}  // namespace
}  // namespace nimbus
