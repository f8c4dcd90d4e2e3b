// Loading the volume data behind vdb and cloud shapes (called by the scene parser).
#pragma once

#include <filesystem>
#include <map>
#include <memory>
#include <string>

#include "nimbus/scene.h"

namespace nimbus {

// Resolves v.file against base_dir and loads the grid into v.data. Errors name the scene file
// (`where`) and the JSON path of the shape as well as the volume file.
void load_vdb_shape(VdbShape& v, const std::filesystem::path& base_dir, const std::string& where,
                    const std::string& json_path);
// Voxelises the procedural cloud into c.data.
void build_cloud_shape(CloudShape& c);

// In-memory density grids by name (the Python module's numpy volumes, docs/python.md): a vdb shape that
// says "volume": NAME instead of "file" takes the grid of that name.
using VolumeTable = std::map<std::string, std::shared_ptr<const DensityGrid>>;
// parse_scene (nimbus/scene.h) with in-memory volumes; without them a `volume` field is an error.
Scene parse_scene(const nlohmann::json& doc, const std::string& name, const std::filesystem::path& base_dir,
                  const VolumeTable& volumes);

}  // namespace nimbus
