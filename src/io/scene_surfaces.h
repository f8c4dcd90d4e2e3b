// Parsing the scene's "surfaces" array (docs/scene-format.md), meshes loaded from their files.
#pragma once

#include <filesystem>

#include "core/json_reader.h"
#include "nimbus/scene.h"

namespace nimbus {

// One element of "surfaces"; relative mesh paths resolve against base_dir.
Surface parse_surface(JsonObject o, const std::filesystem::path& base_dir);

}  // namespace nimbus
