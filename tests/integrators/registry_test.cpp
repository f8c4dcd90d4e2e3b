// The integrator registry: every integrator's settings round-trip through JSON, unknown fields name the
// known ones, and the names are listed once.
#include "integrators/registry.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <set>

#include "integrators/mfs.h"
#include "integrators/octave.h"
#include "integrators/pathtrace.h"
#include "integrators/single.h"
#include "nimbus/error.h"
#include "nimbus/render.h"

namespace nimbus {
namespace {

std::string registry_error(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

// from_json(to_json(from_json(j))) writes the same JSON as from_json(j): nothing is lost or renamed.
template <typename Settings>
void expect_round_trip(Settings (*parse)(const nlohmann::json&, const std::string&),
                       const nlohmann::json& j) {
  const nlohmann::json once = to_json(parse(j, "t.json"));
  const nlohmann::json twice = to_json(parse(once, "t.json"));
  EXPECT_EQ(once, twice) << j.dump();
  // Every field written is a field the parser reads (the keys are the JSON keys), and every field given
  // is written back with its value.
  for (const auto& [key, value] : j.items()) {
    ASSERT_TRUE(once.contains(key)) << key;
    EXPECT_EQ(once[key], value) << key;
  }
}

TEST(Registry, SettingsRoundTripThroughJson) {
  expect_round_trip(&pathtrace_settings_from_json, nlohmann::json::object());
  expect_round_trip(&pathtrace_settings_from_json, {{"max_wide_scatters", 2}, {"peak_fraction", 0.5}});
  expect_round_trip(&single_settings_from_json, nlohmann::json::object());
  expect_round_trip(&single_settings_from_json, {{"tau_step", 0.05},
                                                 {"light_samples", 3},
                                                 {"transmittance", "shadow_map"},
                                                 {"shadow_map_resolution", 32}});
  expect_round_trip(&octave_settings_from_json, nlohmann::json::object());
  expect_round_trip(
      &octave_settings_from_json,
      {{"octaves", 6}, {"a", 0.6}, {"b", 0.4}, {"c", 0.7}, {"tau_step", 0.2}, {"shadow_map_resolution", 16}});
  expect_round_trip(&mfs_settings_from_json, nlohmann::json::object());
  expect_round_trip(&mfs_settings_from_json, {{"tau_step", 0.2},
                                              {"step_growth", 0.5},
                                              {"light_path", "beer_lambert"},
                                              {"propagator", "gaussian"},
                                              {"peak_fraction", 0.8},
                                              {"large_angle_scatters", 2},
                                              {"photons", 1000},
                                              {"photon_transport", "similarity"},
                                              {"channel_passes", true},
                                              {"scatter_grid_resolution", 16},
                                              {"scatter_grid_bands", 2},
                                              {"forward_side", "camera"},
                                              {"beam_photons", 0},
                                              {"beam_smoothing", 0},
                                              {"photon_splat", "stratified"},
                                              {"light_blur", false},
                                              {"path_lengthening", true},
                                              {"camera_fluence", true},
                                              {"filtered_lookups", true},
                                              {"source_blur", true},
                                              {"camera_tilt", false},
                                              {"camera_shift", false},
                                              {"entry_loss", false},
                                              {"peak_toward_camera", true},
                                              {"wide_toward_camera", true},
                                              {"exact_light_transmittance", true},
                                              {"shadow_map_resolution", 32}});
  expect_round_trip(&mfs_settings_from_json, {{"peak_fraction", "auto"},
                                              {"large_angle_scatters", "all"},
                                              {"scatter_grid_resolution", "auto"},
                                              {"beam_photons", "auto"},
                                              {"exact_light_transmittance", "auto"}});
}

TEST(Registry, DefaultsAreWrittenOut) {
  const nlohmann::json mfs = to_json(MfsSettings{});
  EXPECT_EQ(mfs["peak_fraction"], "auto");
  EXPECT_EQ(mfs["large_angle_scatters"], "all");
  EXPECT_EQ(mfs["scatter_grid_resolution"], "auto");
  EXPECT_EQ(mfs["light_path"], "forward");
  EXPECT_EQ(mfs["photon_splat"], "trilinear");
  EXPECT_EQ(mfs["camera_tilt"], true);
  EXPECT_EQ(mfs["camera_shift"], true);
  EXPECT_EQ(mfs["entry_loss"], true);
  EXPECT_EQ(mfs["exact_light_transmittance"], "auto");
  EXPECT_EQ(mfs["beam_spread"], "straight");
  EXPECT_EQ(mfs["beam_photons"], "auto");
  EXPECT_EQ(mfs["beam_smoothing"], 2);
  EXPECT_EQ(mfs["grid_denoise"], true);
  EXPECT_EQ(mfs["grid_lobe_tail"], true);
  EXPECT_EQ(mfs["camera_fluence"], false);
  EXPECT_EQ(mfs["wide_toward_camera"], false);
  EXPECT_EQ(mfs.size(), 31u);  // every option of the table in mfs.h
}

TEST(Registry, UnknownFieldsAndNamesAreErrors) {
  EXPECT_EQ(registry_error([] {
              validate_integrator_options("pathtrace", {{"tau_step", 0.1}}, "s.json");
            }),
            "s.json: /integrator/tau_step: unknown field (known here: max_wide_scatters, peak_fraction)");
  EXPECT_EQ(registry_error([] {
              validate_integrator_options("single", {{"transmittance", "exact"}}, "s.json");
            }),
            "s.json: /integrator/transmittance: must be \"ratio\" or \"shadow_map\"");
  EXPECT_EQ(registry_error([] { find_integrator("volpath"); }),
            "unknown integrator 'volpath' (known: pathtrace, single, mfs, octave)");
  std::vector<std::string> names;
  for (const IntegratorEntry& e : integrator_registry()) {
    names.push_back(e.name);
    EXPECT_FALSE(e.summary.empty()) << e.name;
  }
  EXPECT_EQ(names, integrator_names());
}

}  // namespace
}  // namespace nimbus

namespace nimbus {
namespace {

// The fields of the options table at the top of src/integrators/NAME.h ("// | `field` | ...").
std::set<std::string> table_fields(const std::string& name) {
  std::ifstream in(std::filesystem::path(NIMBUS_SOURCE_DIR) / "src" / "integrators" / (name + ".h"));
  std::set<std::string> fields;
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("// | `", 0) != 0) continue;
    const size_t a = line.find('`') + 1, b = line.find('`', a);
    fields.insert(line.substr(a, b - a));
  }
  return fields;
}

std::set<std::string> keys(const nlohmann::json& j) {
  std::set<std::string> k;
  for (const auto& [key, value] : j.items()) k.insert(key);
  return k;
}

// The tables that open the integrators' headers list exactly the JSON keys their settings read and
// write, and docs/scene-format.md names every one of them.
TEST(Registry, OptionTablesMatchTheJsonKeys) {
  PathTraceSettings pt;
  pt.max_wide_scatters = 1;
  const std::vector<std::pair<std::string, nlohmann::json>> cases = {{"pathtrace", to_json(pt)},
                                                                     {"single", to_json(SingleSettings{})},
                                                                     {"mfs", to_json(MfsSettings{})},
                                                                     {"octave", to_json(OctaveSettings{})}};
  std::ifstream doc(std::filesystem::path(NIMBUS_SOURCE_DIR) / "docs" / "scene-format.md");
  const std::string text((std::istreambuf_iterator<char>(doc)), std::istreambuf_iterator<char>());
  ASSERT_FALSE(text.empty());
  for (const auto& [name, json] : cases) {
    EXPECT_EQ(table_fields(name), keys(json)) << name;
    for (const std::string& k : keys(json))
      EXPECT_NE(text.find("`" + k + "`"), std::string::npos) << name << " " << k;
  }
}

}  // namespace
}  // namespace nimbus
