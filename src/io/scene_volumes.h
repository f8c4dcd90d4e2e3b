// Loading the volume data behind vdb and cloud shapes (called by the scene parser).
#pragma once

#include <filesystem>
#include <string>

#include "nimbus/scene.h"

namespace nimbus {

// Resolves v.file against base_dir and loads the grid into v.data. Errors name the scene file
// (`where`) and the JSON path of the shape as well as the volume file.
void load_vdb_shape(VdbShape& v, const std::filesystem::path& base_dir, const std::string& where,
                    const std::string& json_path);
// Voxelises the procedural cloud into c.data.
void build_cloud_shape(CloudShape& c);

}  // namespace nimbus
