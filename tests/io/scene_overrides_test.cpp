// render --set: a scene field changed before validation, as if written in the file.
#include <gtest/gtest.h>

#include "nimbus/error.h"
#include "nimbus/scene.h"

namespace nimbus {
namespace {

nlohmann::json doc() {
  return nlohmann::json::parse(R"({"camera": {"width": 8, "height": 8},
    "media": [{"sigma_s": 1.0, "shape": {"type": "sphere"}}]})");
}

TEST(SceneOverrides, SetNumbersArraysStringsAndNewKeys) {
  nlohmann::json d = doc();
  apply_scene_override(d, "camera.width=1920");
  apply_scene_override(d, "media.0.sigma_s=[1, 2, 3]");
  apply_scene_override(d, "media.0.shape.file=clouds/frame.0001.vdb");  // not JSON: a string
  apply_scene_override(d, "film.transparent=true");                     // objects made on the way
  apply_scene_override(d, "media.0.shape.type=\"box\"");                // JSON string
  EXPECT_EQ(d["camera"]["width"], 1920);
  EXPECT_EQ(d["camera"]["height"], 8);
  EXPECT_EQ(d["media"][0]["sigma_s"], nlohmann::json::parse("[1, 2, 3]"));
  EXPECT_EQ(d["media"][0]["shape"]["file"], "clouds/frame.0001.vdb");
  EXPECT_EQ(d["media"][0]["shape"]["type"], "box");
  EXPECT_EQ(d["film"]["transparent"], true);
}

TEST(SceneOverrides, BadPathsNameTheOverride) {
  for (const char* bad : {"camera.width", "=3", "media.1.sigma_s=2", "media.x.sigma_s=2", "camera.width.x=1",
                          "camera..width=2", "media.-1.sigma_s=1"}) {
    nlohmann::json d = doc();
    try {
      apply_scene_override(d, bad);
      ADD_FAILURE() << bad << ": no error";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("--set"), std::string::npos) << e.what();
    }
    EXPECT_EQ(d, doc()) << bad << ": the document changed";
  }
}

TEST(SceneOverrides, TheOverriddenSceneIsValidatedAsTheFileIs) {
  nlohmann::json d = builtin_demo_document();
  apply_scene_override(d, "camera.width=40");
  EXPECT_EQ(parse_scene(d, "demo", ".").camera.width, 40);
  apply_scene_override(d, "camera.width=-4");
  EXPECT_THROW(parse_scene(d, "demo", "."), Error);
  d = builtin_demo_document();
  apply_scene_override(d, "camera.bogus=1");
  EXPECT_THROW(parse_scene(d, "demo", "."), Error);
}

}  // namespace
}  // namespace nimbus
