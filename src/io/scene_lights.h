// Parsing the scene's "lights" array (docs/scene-format.md).
#pragma once

#include <filesystem>

#include "core/json_reader.h"
#include "nimbus/scene.h"

namespace nimbus {

// One element of "lights"; a relative file path (an environment image) resolves against base_dir.
Light parse_light(JsonObject o, const std::filesystem::path& base_dir);

}  // namespace nimbus
