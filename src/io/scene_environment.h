// The scene's "environment" light (docs/scene-format.md): a constant radiance or a lat-long HDR image.
#pragma once

#include <filesystem>

#include "core/json_reader.h"
#include "nimbus/image.h"
#include "nimbus/scene.h"

namespace nimbus {

// The fields of an environment light (its "type" already read): either "radiance", or "file" with
// optional "intensity" and "transform" (rotations only); the image is loaded (a relative path resolves
// against base_dir). Errors name the file and the JSON path; the caller calls o.finish().
EnvironmentLight parse_environment_light(JsonObject& o, const std::filesystem::path& base_dir);

// An HDR lat-long image: an OpenEXR file with R, G, B channels of half or float pixels (integer
// channels, other formats, and non-finite pixels are errors; negative values read as 0). Throws
// nimbus::Error naming the file.
Image read_environment_image(const std::filesystem::path& path);

// How many of the lights are environment images.
inline int count_environment_images(const std::vector<Light>& lights) {
  int n = 0;
  for (const Light& l : lights)
    if (const auto* e = std::get_if<EnvironmentLight>(&l); e && e->map) ++n;
  return n;
}

}  // namespace nimbus
