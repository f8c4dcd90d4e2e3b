// Small field readers shared by the scene parser's media, surfaces, lights and volumes.
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

// A vector field that must not be zero (a direction, an up vector); not normalised.
inline Vec3 nonzero_vec3(JsonObject& o, const std::string& key, const Vec3& fallback) {
  const Vec3 v = o.vec3(key, fallback);
  if (!(length(v) > 1e-12)) o.fail(key, "must have non-zero length");
  return v;
}

// A required direction, normalised.
inline Vec3 unit_direction(JsonObject& o, const std::string& key) {
  const Vec3 d = o.vec3(key);
  const double len = length(d);
  if (!(len > 1e-12)) o.fail(key, "must have non-zero length");
  return d / len;
}

// A box's "min" and "max" corners; max must exceed min on every axis.
inline void read_box_corners(JsonObject& o, Vec3* min, Vec3* max) {
  *min = o.vec3("min");
  *max = o.vec3("max");
  for (int a = 0; a < 3; ++a)
    if (!((*max)[a] > (*min)[a])) o.fail("max", "must exceed min on every axis");
}

}  // namespace nimbus
