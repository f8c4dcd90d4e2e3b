// render --set: one field of a scene document changed before validation (nimbus/scene.h).
#include <fmt/format.h>

#include <cctype>
#include <string>

#include "nimbus/error.h"
#include "nimbus/scene.h"

namespace nimbus {

namespace {

bool is_index(const std::string& key) {
  if (key.empty() || key.size() > 9) return false;
  for (char c : key)
    if (!std::isdigit(static_cast<unsigned char>(c))) return false;
  return true;
}

}  // namespace

void apply_scene_override(nlohmann::json& doc, const std::string& assignment) {
  const size_t eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0)
    throw Error(fmt::format("--set '{}': expected PATH=VALUE, e.g. camera.width=1920", assignment));
  const std::string path = assignment.substr(0, eq), text = assignment.substr(eq + 1);
  nlohmann::json value = nlohmann::json::parse(text, nullptr, false);
  if (value.is_discarded()) value = text;  // not JSON: a string (a file name, a type)
  nlohmann::json* node = &doc;
  std::string walked;
  size_t start = 0;
  while (true) {
    const size_t dot = path.find('.', start);
    const std::string key = path.substr(start, dot == std::string::npos ? std::string::npos : dot - start);
    if (key.empty()) throw Error(fmt::format("--set {}: empty name in the path", path));
    if (node->is_null()) *node = nlohmann::json::object();  // made on the way
    if (node->is_array()) {
      if (!is_index(key) || std::stoul(key) >= node->size())
        throw Error(fmt::format("--set {}: {} has {} elements; '{}' is not one of their indices", path,
                                walked.empty() ? "the scene" : walked, node->size(), key));
      node = &(*node)[std::stoul(key)];
    } else if (node->is_object()) {
      node = &(*node)[key];
    } else {
      throw Error(
          fmt::format("--set {}: {} is a {}, not an object or array", path, walked, node->type_name()));
    }
    walked += (walked.empty() ? "" : ".") + key;
    if (dot == std::string::npos) break;
    start = dot + 1;
  }
  *node = std::move(value);
}

}  // namespace nimbus
