// The spot, sphere and rectangle lights in the scene's "lights" array (src/io/scene_area_lights.cpp):
// fields, power turned into radiance, transforms baked in, and the exact message for each bad field (and
// exit code 2 from the CLI, nothing written).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "core/math.h"
#include "nimbus/error.h"
#include "nimbus/scene.h"
#include "support/scenes.h"
#include "support/scratch_dir.h"

namespace nimbus {
namespace {

Scene with_light(const std::string& light) {
  return test::scene_from_json("{" + test::camera_json() + R"(, "media": [], "lights": [)" + light + "]}");
}

std::string light_error(const std::string& light) {
  try {
    with_light(light);
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

constexpr const char* kSpot =
    R"({"type": "spot", "position": [0, 0, 2], "direction": [0, 0, -2], "intensity": 3, "cone_angle_deg": 50)";
constexpr const char* kSphere = R"({"type": "sphere", "center": [0, 0, 2], "radius": 0.5)";
constexpr const char* kRect =
    R"({"type": "rectangle", "center": [0, 0, 2], "normal": [0, 0, -1], "up": [0, 1, 0], "size": [2, 0.5])";

TEST(SceneLights, SpotFieldsAndTransform) {
  const Scene s = with_light(std::string(kSpot) + R"(, "blend": 0.25,
      "transform": {"rotate": [{"axis": [1, 0, 0], "degrees": 90}], "translate": [1, 0, 0]}})");
  const auto& spot = std::get<SpotLight>(s.lights[0]);
  EXPECT_NEAR(spot.position.x, 1.0, 1e-12);
  EXPECT_NEAR(spot.position.y, -2.0, 1e-12);  // (0, 0, 2) turned about x by 90 degrees
  EXPECT_NEAR(spot.direction.y, 1.0, 1e-12);
  EXPECT_EQ(spot.cone_angle_deg, 50.0);
  EXPECT_EQ(spot.blend, 0.25);
  EXPECT_EQ(spot.intensity, Rgb(3.0));
  EXPECT_EQ(std::get<SpotLight>(with_light(std::string(kSpot) + "}").lights[0]).blend, 0.0);
}

TEST(SceneLights, PowerBecomesRadiance) {
  const auto sphere = std::get<SphereLight>(with_light(std::string(kSphere) + R"(, "power": 10})").lights[0]);
  EXPECT_NEAR(sphere.radiance.x, 10.0 / (4.0 * kPi * kPi * 0.25), 1e-12);  // P = 4 pi^2 r^2 L
  EXPECT_FALSE(sphere.visible);
  const auto rect = std::get<RectangleLight>(with_light(std::string(kRect) + R"(, "power": [3, 6, 9],
      "visible": true})")
                                                 .lights[0]);
  EXPECT_NEAR(rect.radiance.z, 9.0 / (kPi * 1.0), 1e-12);  // P = pi A L
  EXPECT_TRUE(rect.visible);
  // With a uniform scale, the power is the scaled light's.
  const auto scaled = std::get<SphereLight>(
      with_light(std::string(kSphere) + R"(, "power": 10, "transform": {"scale": 2}})").lights[0]);
  EXPECT_NEAR(scaled.radius, 1.0, 1e-12);
  EXPECT_NEAR(scaled.center.z, 4.0, 1e-12);
  EXPECT_NEAR(scaled.radiance.x, 10.0 / (4.0 * kPi * kPi), 1e-12);
}

TEST(SceneLights, RectangleFrameIsOrthonormalAfterItsTransform) {
  const auto r = std::get<RectangleLight>(with_light(R"({"type": "rectangle", "center": [0, 0, 2],
      "normal": [0, 0, -1], "up": [0, 1, 1], "size": [2, 1], "radiance": 1,
      "transform": {"rotate": [{"axis": [0, 0, 1], "degrees": 90}], "scale": 3}})")
                                              .lights[0]);
  EXPECT_NEAR(dot(r.normal, r.up), 0.0, 1e-12);
  EXPECT_NEAR(length(r.up), 1.0, 1e-12);
  EXPECT_NEAR(r.up.x, -1.0, 1e-12);  // (0, 1, 0) after 90 degrees about z
  EXPECT_NEAR(r.width, 6.0, 1e-12);
  EXPECT_NEAR(r.height, 3.0, 1e-12);
}

TEST(SceneLights, BadFieldsAreNamed) {
  const std::string at = "test.json: /lights/0/";
  const std::string spot =
      R"({"type": "spot", "position": [0, 0, 2], "direction": [0, 0, -1], "intensity": 1)";
  EXPECT_EQ(light_error(spot + R"(, "cone_angle_deg": 0})"), at + "cone_angle_deg: must be > 0");
  EXPECT_EQ(light_error(spot + R"(, "cone_angle_deg": 200})"), at + "cone_angle_deg: must be <= 180");
  EXPECT_EQ(light_error(spot + R"(, "cone_angle_deg": 30, "blend": 1.5})"), at + "blend: must be <= 1");
  EXPECT_EQ(light_error(spot + "}"), at + "cone_angle_deg: required field is missing");
  EXPECT_EQ(light_error(std::string(kSphere) + R"(, "radiance": -1})"), at + "radiance: must be >= 0");
  EXPECT_EQ(light_error(std::string(kSphere) + R"(, "radiance": 1, "power": 2})"),
            at + "power: give either radiance or power, not both");
  EXPECT_EQ(light_error(std::string(kSphere) + "}"),
            "test.json: /lights/0: an area light needs \"radiance\" or \"power\"");
  EXPECT_EQ(light_error(R"({"type": "sphere", "center": [0, 0, 2], "radius": 0, "radiance": 1})"),
            at + "radius: must be > 0");
  EXPECT_EQ(light_error(R"({"type": "rectangle", "center": [0, 0, 2], "normal": [0, 0, -1], "up": [0, 1, 0],
      "size": [0, 1], "radiance": 1})"),
            at + "size: both sides must be > 0 and finite");
  EXPECT_EQ(light_error(R"({"type": "rectangle", "center": [0, 0, 2], "normal": [0, 0, -1], "up": [0, 0, 1],
      "size": [1, 1], "radiance": 1})"),
            at + "up: must not be parallel to the normal");
  EXPECT_EQ(light_error(std::string(kRect) + R"(, "power": -3})"), at + "power: must be >= 0");
  EXPECT_EQ(light_error(std::string(kSphere) + R"(, "radiance": 1, "transform": {"scale": [1, 2, 1]}})"),
            at + "transform: must be rotations, one uniform scale and a translation for an area light");
  EXPECT_EQ(light_error(std::string(kRect) + R"(, "radiance": 1, "visibl": true})").substr(0, at.size() + 14),
            at + "visibl: unknow");
}

TEST(SceneLights, TheCliRefusesABadConeWithExitCode2) {
  test::ScratchDir dir("lights_cli");
  std::ofstream(dir / "s.json") << "{" + test::camera_json() + R"(, "media": [], "lights": [
      {"type": "spot", "position": [0, 0, 2], "direction": [0, 0, -1], "intensity": 1, "cone_angle_deg": 200}]})";
  const std::string cmd =
      fmt::format("{} render {} -o {} --quiet 2> {}", NIMBUS_CLI, (dir / "s.json").string(),
                  (dir / "o.exr").string(), (dir / "err.txt").string());
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 2);
  std::ifstream err(dir / "err.txt");
  const std::string text{std::istreambuf_iterator<char>(err), std::istreambuf_iterator<char>()};
  EXPECT_NE(text.find("s.json: /lights/0/cone_angle_deg: must be <= 180"), std::string::npos) << text;
  EXPECT_FALSE(std::filesystem::exists(dir / "o.exr"));
}

}  // namespace
}  // namespace nimbus
