// The bad-input catalogue, second part (tests/io/scene_test.cpp holds the field-by-field messages):
// the awkward-but-valid scenes render (camera or light inside a medium, no media at all, for every
// integrator), and the limits that used to be checked late or not by name are errors that name the
// file and the field (spp above kMaxSpp, more than 16 media, grids with no active voxels, degenerate
// camera frames). The outcome of each is documented in docs/scene-format.md ("Edge cases").
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nanovdb/util/IO.h>
#include <nanovdb/util/OpenToNanoVDB.h>
#include <openvdb/openvdb.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <fstream>

#include "io/vdb_test_util.h"
#include "nimbus/error.h"
#include "nimbus/render.h"
#include "support/scenes.h"

namespace nimbus {
namespace {

// A sphere of radius 1 at the origin (albedo ~0.95, forward scattering), sun, sky and a point light.
std::string bad_input_sphere_scene(const std::string& camera_pos, const std::string& point_pos,
                                   const std::string& integrator) {
  return fmt::format(R"({{"camera": {{"position": {}, "look_at": [0, 1, 0], "up": [0, 0, 1], "fov_y_deg": 60,
      "width": 8, "height": 8}},
    "media": [{{"shape": {{"type": "sphere", "center": [0, 0, 0], "radius": 1}}, "sigma_s": 3.0,
                "sigma_a": 0.15, "phase": {{"type": "hg", "g": 0.8}}}}],
    "lights": [{{"type": "directional", "direction": [0.3, 1, -0.5], "irradiance": 1.0}},
               {{"type": "point", "position": {}, "intensity": 1.0}},
               {{"type": "environment", "radiance": 0.2}}],
    "integrator": {{"type": "{}", "spp": 4}}}})",
                     camera_pos, point_pos, integrator);
}

void expect_finite_and_lit(const std::string& json, const std::string& what) {
  const RenderResult r = render(test::scene_from_json(json));
  EXPECT_EQ(r.nonfinite_samples, 0) << what;
  double sum = 0;
  for (float v : r.image.rgb) {
    ASSERT_TRUE(std::isfinite(v)) << what;
    ASSERT_GE(v, 0.0f) << what;
    sum += v;
  }
  EXPECT_GT(sum, 0.0) << what;
}

std::string bad_input_parse_error(const nlohmann::json& doc) {
  try {
    parse_scene(doc, "scene.json", ".");
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

nlohmann::json small_scene() {
  return nlohmann::json::parse("{" + test::camera_json() + R"(,
    "media": [{"shape": {"type": "sphere", "radius": 1}, "sigma_s": 1.0}],
    "lights": [{"type": "environment", "radiance": 1.0}]})");
}

TEST(BadInput, CameraInsideAMediumRendersWithEveryIntegrator) {
  for (const std::string& name : integrator_names())
    expect_finite_and_lit(bad_input_sphere_scene("[0, -0.3, 0.1]", "[0, 0, 3]", name),
                          "camera inside, " + name);
}

TEST(BadInput, LightInsideAMediumRendersWithEveryIntegrator) {
  for (const std::string& name : integrator_names())
    expect_finite_and_lit(bad_input_sphere_scene("[0, -4, 0]", "[0.1, 0.2, 0.3]", name),
                          "point light inside, " + name);
}

TEST(BadInput, NoMediaShowsTheEnvironmentWithEveryIntegrator) {
  for (const std::string& name : integrator_names()) {
    const Scene scene = test::scene_from_json("{" + test::camera_json(6, 5) + R"(, "media": [],
      "lights": [{"type": "directional", "direction": [0, 0, -1], "irradiance": 5.0},
                 {"type": "environment", "radiance": [0.1, 0.2, 0.3]}],
      "integrator": {"type": ")" + name + R"(", "spp": 2}})");
    const RenderResult r = render(scene);
    for (int y = 0; y < 5; ++y)
      for (int x = 0; x < 6; ++x)
        for (int c = 0; c < 3; ++c) ASSERT_FLOAT_EQ(r.image.pixel(x, y)[c], 0.1f * (c + 1)) << name;
    // No lights either: black.
    const Scene dark = test::scene_from_json("{" + test::camera_json(4, 4) + R"(, "media": [], "lights": [],
      "integrator": {"type": ")" + name + R"(", "spp": 1}})");
    for (float v : render(dark).image.rgb) ASSERT_EQ(v, 0.0f) << name;
  }
}

TEST(BadInput, SppAboveTheLimitNamesTheField) {
  nlohmann::json doc = small_scene();
  doc["integrator"] = {{"spp", kMaxSpp + 1}};
  EXPECT_EQ(bad_input_parse_error(doc), fmt::format("scene.json: /integrator/spp: must be <= {}", kMaxSpp));
  doc["integrator"]["spp"] = 1e30;
  EXPECT_EQ(bad_input_parse_error(doc), fmt::format("scene.json: /integrator/spp: must be <= {}", kMaxSpp));
  // The RenderOptions override (what --spp sets) is checked by render() too.
  doc["integrator"]["spp"] = 1;
  RenderOptions opt;
  opt.spp = kMaxSpp + 1;
  try {
    render(parse_scene(doc, "scene.json", "."), opt);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), fmt::format("spp must be between 1 and {}", kMaxSpp));
  }
  // The CLI refuses it while parsing its arguments, naming the option, with exit code 2.
  test::ScratchDir dir("bad_spp");
  std::ofstream(dir / "s.json") << doc.dump();
  const std::string cmd =
      fmt::format("{} render {} -o {} --spp {} --quiet 2> {}", NIMBUS_CLI, (dir / "s.json").string(),
                  (dir / "o.exr").string(), kMaxSpp + 1, (dir / "err.txt").string());
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 2);
  std::ifstream err(dir / "err.txt");
  const std::string text{std::istreambuf_iterator<char>(err), std::istreambuf_iterator<char>()};
  EXPECT_NE(text.find("--spp"), std::string::npos) << text;
  EXPECT_FALSE(std::filesystem::exists(dir / "o.exr"));
}

TEST(BadInput, MoreThanSixteenMediaIsAParseError) {
  nlohmann::json doc = small_scene();
  for (int i = 0; i < 16; ++i) doc["media"].push_back(doc["media"][0]);
  EXPECT_EQ(bad_input_parse_error(doc), "scene.json: /media: at most 16 media (got 17)");
  doc["media"].erase(doc["media"].begin());
  EXPECT_EQ(bad_input_parse_error(doc), "(no error)");
}

TEST(BadInput, GridsWithoutActiveVoxelsAreErrors) {
  openvdb::initialize();
  test::ScratchDir dir("bad_grid");
  auto empty = openvdb::FloatGrid::create(0.0f);
  empty->setName("density");
  for (auto codec : {nanovdb::io::Codec::NONE, nanovdb::io::Codec::ZIP, nanovdb::io::Codec::BLOSC}) {
    const auto file = dir / "empty.nvdb";
    nanovdb::io::writeGrid(file.string(), nanovdb::openToNanoVDB(*empty), codec);
    const std::string msg = test::load_error(file);
    EXPECT_NE(msg.find("empty.nvdb: "), std::string::npos) << msg;
    EXPECT_NE(msg.find("empty"), std::string::npos) << msg;
  }
  // Through a scene: the error names the scene, the field and the volume file.
  nlohmann::json doc = small_scene();
  doc["media"][0]["shape"] = {{"type", "vdb"}, {"file", (dir / "empty.nvdb").string()}, {"scale", 1.0}};
  const std::string msg = bad_input_parse_error(doc);
  EXPECT_EQ(msg.rfind("scene.json: /media/0/shape/file: " + (dir / "empty.nvdb").string() + ": ", 0), 0u)
      << msg;
  // A procedural cloud has at least 8 voxels along each axis.
  doc["media"][0]["shape"] = {{"type", "cloud"}, {"radius", 1}, {"resolution", 0}};
  EXPECT_EQ(bad_input_parse_error(doc), "scene.json: /media/0/shape/resolution: must be >= 8");
}

// A scene may name any path as a volume: devices, FIFOs and directories are refused from their file
// status, before anything is opened (opening a FIFO for reading would block until a writer comes).
TEST(BadInput, VolumePathsThatAreNotRegularFilesAreRefusedWithoutOpening) {
  test::ScratchDir dir("bad_volume_path");
  const auto fifo = dir / "pipe.vdb";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"/dev/zero", "not a regular file"},
      {fifo.string(), "not a regular file"},
      {dir.path.string(), "is a directory"},
  };
  for (const auto& [path, what] : cases) {
    nlohmann::json doc = small_scene();
    doc["media"][0]["shape"] = {{"type", "vdb"}, {"file", path}, {"scale", 1.0}};
    EXPECT_EQ(bad_input_parse_error(doc).rfind("scene.json: /media/0/shape/file: " + path + ": " + what, 0),
              0u)
        << bad_input_parse_error(doc);
  }
}

TEST(BadInput, DegenerateCameraFramesAreErrors) {
  nlohmann::json doc = small_scene();
  doc["camera"]["look_at"] = doc["camera"]["position"];
  EXPECT_EQ(bad_input_parse_error(doc), "scene.json: /camera/look_at: must differ from position");
  doc = small_scene();
  const std::string parallel =
      "scene.json: /camera/up: must not be parallel to the view direction (look_at - position)";
  for (const auto& up :
       {nlohmann::json{0, -3, 0}, nlohmann::json{0, 1, 1e-9}}) {  // anti-parallel, nearly parallel
    doc["camera"]["up"] = up;
    EXPECT_EQ(bad_input_parse_error(doc), parallel) << up;
  }
  doc["camera"]["up"] = {0, 0, 0};
  EXPECT_EQ(bad_input_parse_error(doc), "scene.json: /camera/up: must have non-zero length");
  doc["camera"]["up"] = {0, 1, 0.01};  // nearly, but not quite, parallel: a valid (tilted) frame
  EXPECT_EQ(bad_input_parse_error(doc), "(no error)");
}

}  // namespace
}  // namespace nimbus
