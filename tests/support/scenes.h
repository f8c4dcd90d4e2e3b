// Small scenes for tests, built from JSON text.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "nimbus/scene.h"

namespace nimbus::test {

inline Scene scene_from_json(const std::string& text) {
  return parse_scene(nlohmann::json::parse(text), "test.json", ".");
}

// A camera block for a w x h image looking from -y at the origin.
inline std::string camera_json(int w = 8, int h = 8, double fov = 30.0, double distance = 5.0) {
  return R"("camera": {"position": [0, )" + std::to_string(-distance) +
         R"(, 0], "look_at": [0, 0, 0], "up": [0, 0, 1], "fov_y_deg": )" + std::to_string(fov) +
         R"(, "width": )" + std::to_string(w) + R"(, "height": )" + std::to_string(h) + "}";
}

}  // namespace nimbus::test
