// The scene parser: the documented contract parses, and every kind of bad input gives an error that
// names the file and the JSON path, with the exact message users see.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "core/math.h"
#include "media/phase.h"
#include "nimbus/error.h"
#include "support/scenes.h"
#include "transport/phase_spec.h"

namespace nimbus {
namespace {

const char* kGood = R"({
  "camera": {"position": [0, -5, 0], "look_at": [0, 0, 0], "up": [0, 0, 1],
             "fov_y_deg": 40, "width": 32, "height": 24},
  "media": [
    {"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1},
     "sigma_s": 2.0, "sigma_a": 0.05, "phase": {"type": "hg", "g": 0.85}},
    {"shape": {"type": "box", "min": [-1, -1, -1], "max": [1, 1, 1]},
     "sigma_s": [1.5, 2.0, 2.5], "sigma_a": 0.0, "phase": {"type": "isotropic"}}
  ],
  "lights": [
    {"type": "directional", "direction": [-0.354, 0.612, -0.707], "irradiance": 1.0, "angular_diameter_deg": 0},
    {"type": "point", "position": [0, 0, 5], "intensity": [10, 10, 10]},
    {"type": "environment", "radiance": [0.1, 0.2, 0.4]}
  ],
  "integrator": {"type": "pathtrace", "spp": 256, "max_events": 0, "seed": 1}
})";

TEST(Scene, ParsesTheContract) {
  const Scene s = test::scene_from_json(kGood);
  EXPECT_EQ(s.camera.width, 32);
  EXPECT_EQ(s.camera.height, 24);
  ASSERT_EQ(s.media.size(), 2u);
  EXPECT_DOUBLE_EQ(s.media[0].sigma_s.x, 2.0);
  EXPECT_DOUBLE_EQ(s.media[1].sigma_s.z, 2.5);
  EXPECT_DOUBLE_EQ(std::get<HgPhase>(s.media[0].phase).g, 0.85);
  ASSERT_EQ(s.lights.size(), 3u);
  const auto& d = std::get<DirectionalLight>(s.lights[0]);
  EXPECT_NEAR(length(d.direction), 1.0, 1e-12);
  EXPECT_EQ(s.integrator.spp, 256);
}

// Replaces the value at a JSON pointer of the good scene (or removes it with a null patch value).
std::string message_for(const std::string& pointer, const nlohmann::json& value, bool remove = false) {
  nlohmann::json doc = nlohmann::json::parse(kGood);
  if (remove) {
    const nlohmann::json::json_pointer p(pointer);
    doc[p.parent_pointer()].erase(p.back());
  } else {
    doc[nlohmann::json::json_pointer(pointer)] = value;
  }
  try {
    parse_scene(doc, "scene.json", ".");
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(Scene, BadInputCatalogue) {
  using nlohmann::json;
  struct Case {
    std::string pointer;
    json value;
    bool remove;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {"/media/0/sigma_s", -1.0, false, "scene.json: /media/0/sigma_s: must be >= 0"},
      {"/media/1/sigma_s", json::array({1.0, -2.0, 1.0}), false,
       "scene.json: /media/1/sigma_s/1: must be >= 0"},
      {"/media/0/sigma_a", "a lot", false,
       "scene.json: /media/0/sigma_a: must be a number or an array [r, g, b]"},
      {"/media/0/sigma_s", nullptr, true, "scene.json: /media/0/sigma_s: required field is missing"},
      {"/media/0/phase/g", 1.0, false, "scene.json: /media/0/phase/g: must satisfy |g| < 1"},
      {"/media/0/phase/g", -1.5, false, "scene.json: /media/0/phase/g: must satisfy |g| < 1"},
      {"/media/0/phase/type", "rayleigh", false,
       "scene.json: /media/0/phase/type: unknown phase function 'rayleigh' (known: isotropic, hg, double_hg, "
       "gauss, fournier_forand, mie)"},
      {"/media/0/shape/radius", 0.0, false, "scene.json: /media/0/shape/radius: must be > 0"},
      {"/media/0/shape/type", "torus", false,
       "scene.json: /media/0/shape/type: unknown shape 'torus' (known: sphere, box, vdb, cloud)"},
      {"/media/1/shape/max", json::array({1, -2, 1}), false,
       "scene.json: /media/1/shape/max: must exceed min on every axis"},
      {"/media/0/sigm_s", 1.0, false,
       "scene.json: /media/0/sigm_s: unknown field (known here: color_grid, emission, emission_grid, "
       "intensity, phase, shape, sigma_a, sigma_s, "
       "temperature_grid, temperature_offset, temperature_scale, transform)"},
      {"/lights/0/direction", json::array({0, 0, 0}), false,
       "scene.json: /lights/0/direction: must have non-zero length"},
      {"/lights/0/direction", json::array({0, 1}), false,
       "scene.json: /lights/0/direction: must be an array of 3 numbers"},
      {"/lights/0/irradiance", -1.0, false, "scene.json: /lights/0/irradiance: must be >= 0"},
      {"/lights/1/type", "torch", false,
       "scene.json: /lights/1/type: unknown light 'torch' (known: directional, point, environment, spot, "
       "sphere, rectangle)"},
      {"/camera/width", 0, false, "scene.json: /camera/width: must be >= 1"},
      {"/camera/width", 12.5, false, "scene.json: /camera/width: must be a whole number"},
      {"/camera/height", 20000, false, "scene.json: /camera/height: must be <= 16384"},
      {"/camera/fov_y_deg", 180, false, "scene.json: /camera/fov_y_deg: must be <= 179"},
      {"/camera/look_at", json::array({0, -5, 0}), false,
       "scene.json: /camera/look_at: must differ from position"},
      {"/camera/up", json::array({0, 2, 0}), false,
       "scene.json: /camera/up: must not be parallel to the view direction (look_at - position)"},
      {"/camera", nullptr, true, "scene.json: /camera: required field is missing"},
      {"/integrator/spp", 0, false, "scene.json: /integrator/spp: must be >= 1"},
      {"/integrator/type", "magic", false,
       "scene.json: /integrator/type: unknown integrator 'magic' (known: pathtrace, single, mfs, octave)"},
      {"/integrator/tau_step", 0.1, false,
       "scene.json: /integrator/tau_step: unknown field (known here: max_wide_scatters, peak_fraction)"},
      {"/integrator/max_events", -1, false, "scene.json: /integrator/max_events: must be >= 0"},
      {"/media", json::object(), false, "scene.json: /media: must be an array, not an object"},
      {"/media/0", 3, false, "scene.json: /media/0: must be an object, not a number"},
      {"/extra", 1, false,
       "scene.json: /extra: unknown field (known here: camera, integrator, lights, media)"},
  };
  for (const Case& c : cases) {
    EXPECT_EQ(message_for(c.pointer, c.value, c.remove), c.expected) << c.pointer;
  }
}

// A Mie table of data/phase by name: the same phase function as the CLI's mie:NAME; a path, an unknown name or
// no name is an error that names the field.
TEST(Scene, MiePhaseByTableName) {
  nlohmann::json doc = nlohmann::json::parse(kGood);
  doc["media"][0]["phase"] = {{"type", "mie"}, {"table", "cloud_mie_550nm"}};
  const Scene s = parse_scene(doc, "scene.json", ".");
  const auto& t = std::get<TabulatedPhase>(s.media[0].phase);
  const Phase cli = parse_phase_spec("mie:cloud_mie_550nm");
  EXPECT_EQ(t.value, std::get<TabulatedPhase>(cli).value);
  EXPECT_NEAR(phase_mean_cosine(s.media[0].phase), 0.864, 1e-3);  // the table's header: g = 0.86395
  for (const auto& [table, says] :
       std::vector<std::pair<std::string, std::string>>{{"../phase/cloud_mie_550nm", "is not a table name"},
                                                        {"/tmp/cloud.csv", "is not a table name"},
                                                        {"", "is not a table name"},
                                                        {"no_such_table", "no table 'no_such_table'"}}) {
    const std::string got = message_for("/media/0/phase", {{"type", "mie"}, {"table", table}});
    EXPECT_EQ(got.rfind("scene.json: /media/0/phase/table: ", 0), 0u) << got;
    EXPECT_NE(got.find(says), std::string::npos) << got;
  }
  EXPECT_EQ(message_for("/media/0/phase", {{"type", "mie"}}),
            "scene.json: /media/0/phase/table: required field is missing");
}

TEST(Scene, NonFiniteNumbersAreRejected) {
  EXPECT_EQ(message_for("/media/0/sigma_s", std::numeric_limits<double>::infinity()),
            "scene.json: /media/0/sigma_s: must be finite");
  EXPECT_EQ(message_for("/lights/2/radiance/1", std::numeric_limits<double>::quiet_NaN()),
            "scene.json: /lights/2/radiance/1: must be finite");
}

TEST(Scene, ImageBuffersBeyondTheMemoryLimitAreRejected) {
  nlohmann::json doc = nlohmann::json::parse(kGood);
  doc["camera"]["width"] = 16384;
  doc["camera"]["height"] = 16384;
  try {
    parse_scene(doc, "scene.json", ".");
    FAIL();
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "scene.json: /camera/height: width x height exceeds the limit of 67108864 pixels");
  }
}

TEST(Scene, FileErrorsNameTheFile) {
  const auto dir = std::filesystem::temp_directory_path() / "nimbus_scene_test";
  std::filesystem::create_directories(dir);
  const auto bad = dir / "broken.json";
  std::ofstream(bad) << "{\"camera\": [1, 2,";
  std::ofstream(dir / "overflow.json") << "{\"camera\": 1e999}";
  try {
    load_scene(dir / "overflow.json");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind((dir / "overflow.json").string() + ": not valid JSON", 0), 0u)
        << e.what();
  }
  try {
    load_scene(bad);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind(bad.string() + ": not valid JSON", 0), 0u) << e.what();
  }
  try {
    load_scene(dir / "missing.json");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), (dir / "missing.json").string() + ": no such file");
  }
}

// The CLI: a bad scene exits with code 2, names file and field, and creates no output.
TEST(SceneCli, BadSceneExitsTwoWithoutOutput) {
  const auto dir = std::filesystem::temp_directory_path() / "nimbus_scene_cli_test";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  nlohmann::json doc = nlohmann::json::parse(kGood);
  doc["media"][0]["sigma_s"] = -1.0;
  std::ofstream(dir / "bad.json") << doc.dump();
  const std::string out = (dir / "out.exr").string();
  const std::string cmd = std::string(NIMBUS_CLI) + " render " + (dir / "bad.json").string() + " -o " + out +
                          " --quiet 2> " + (dir / "err.txt").string();
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 2);
  std::ifstream err(dir / "err.txt");
  std::string line;
  std::getline(err, line);
  EXPECT_EQ(line, "nimbus: error: " + (dir / "bad.json").string() + ": /media/0/sigma_s: must be >= 0");
  EXPECT_FALSE(std::filesystem::exists(out));
}

}  // namespace
}  // namespace nimbus
