// libFuzzer target: scene JSON text -> nlohmann::json::parse -> nimbus::parse_scene (validation,
// integrator options, volume loading). A nimbus::Error (or a JSON syntax error, which load_scene turns
// into one) is a clean rejection; anything else escaping, a sanitizer report, a leak or a timeout is a
// bug. Relative volume paths resolve against fuzz/data/ (tiny .nvdb/.vdb grids), so seeds load real
// grids quickly. Procedural clouds are capped at 32^3 voxels here (the parser allows 1024^3, which is
// legitimately seconds of work, not a bug): the harness lowers "resolution" before parsing.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "nimbus/error.h"
#include "nimbus/scene.h"

namespace {

// Lowers every cloud "resolution" above 32 to 32 (keeps one parse well under a second).
void cap_cloud_resolution(nlohmann::json& doc) {
  if (!doc.is_object()) return;
  const auto media = doc.find("media");
  if (media == doc.end() || !media->is_array()) return;
  for (auto& m : *media) {
    if (!m.is_object()) continue;
    const auto shape = m.find("shape");
    if (shape == m.end() || !shape->is_object()) continue;
    const auto res = shape->find("resolution");
    if (res != shape->end() && res->is_number() && res->get<double>() > 32) *res = 32;
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::filesystem::path base_dir = std::filesystem::path(NIMBUS_SOURCE_DIR) / "fuzz" / "data";
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(data, data + size);
  } catch (const nlohmann::json::exception&) {
    return 0;  // load_scene reports this as "not valid JSON"
  }
  cap_cloud_resolution(doc);
  try {
    const nimbus::Scene scene = nimbus::parse_scene(doc, "fuzz.json", base_dir);
    (void)scene;
  } catch (const nimbus::Error&) {
  }
  return 0;
}
