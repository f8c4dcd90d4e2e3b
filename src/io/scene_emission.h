// A medium's emission block (docs/scene-format.md, "Emission"): parsed and its grids loaded.
#pragma once

#include <filesystem>

#include "core/json_reader.h"
#include "nimbus/scene.h"

namespace nimbus {

// Reads the emission fields of medium object o (emission, emission_grid, temperature_grid,
// temperature_scale, temperature_offset, intensity, color_grid) into m.emission and loads the grids they
// name from the file of m's vdb shape. Errors (nimbus::Error) name the scene file and the field: a grid
// named on a shape without a file, a grid absent from the file, negative emission or temperatures.
void parse_medium_emission(JsonObject& o, Medium& m, const std::filesystem::path& base_dir);

}  // namespace nimbus
