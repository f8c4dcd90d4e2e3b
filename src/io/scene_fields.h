// Small field readers shared by the scene parser's media, surfaces and volumes.
#pragma once

#include <filesystem>
#include <string>

#include "core/json_reader.h"

namespace nimbus {

// A file named in the scene: absolute as written, else relative to the scene file's folder.
inline std::filesystem::path resolve_scene_path(const std::filesystem::path& base_dir,
                                                const std::string& file) {
  const std::filesystem::path p(file);
  return p.is_absolute() ? p : base_dir / p;
}

// A box's "min" and "max" corners; max must exceed min on every axis.
inline void read_box_corners(JsonObject& o, Vec3* min, Vec3* max) {
  *min = o.vec3("min");
  *max = o.vec3("max");
  for (int a = 0; a < 3; ++a)
    if (!((*max)[a] > (*min)[a])) o.fail("max", "must exceed min on every axis");
}

}  // namespace nimbus
