// Volume files: the float density grid of an OpenVDB file (.vdb, converted once to NanoVDB) or a
// NanoVDB file (.nvdb: uncompressed, ZIP or BLOSC), read with every size and node pointer checked
// against the file, then handed to the in-memory DensityGrid (media/density_grid.h); and the list of a
// file's grids for `nimbus info`. Every error is a nimbus::Error that names the file.
//
// This header does not include OpenVDB (only the header-only NanoVDB core); the OpenVDB reader lives in
// vdb_openvdb.cpp.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "core/math.h"
#include "media/density_grid.h"

namespace nimbus {

// Loads the float grid `grid_name` of `file` ("" = the first float grid of the file). A .nvdb grid's
// checksum is verified. Besides the structure, the values are checked as DensityGrid::from_nanovdb
// does (empty grid, bbox size, NaN/inf).
DensityGrid load_density_grid(const std::filesystem::path& file, const std::string& grid_name = "");

// The vec3 grid `grid_name` of an OpenVDB (.vdb) file as three float grids (its x, y, z components), each
// checked as load_density_grid checks a float grid. A .nvdb file is an error (vec3 grids are read from
// OpenVDB files only).
std::array<DensityGrid, 3> load_vec3_grid(const std::filesystem::path& file, const std::string& grid_name);

// One grid of a volume file, as `nimbus info` shows it (read without converting non-float grids).
struct GridInfo {
  std::string name;        // "" when unnamed
  std::string type;        // value type: "float", "double", "vec3s", ...
  std::string grid_class;  // "fog volume", "level set", "unknown", ...
  uint64_t active_voxels = 0;
  uint64_t tiles = 0;                           // active tiles
  bool empty = true;                            // no active values (bboxes then meaningless)
  std::array<int, 3> index_min{}, index_max{};  // inclusive voxel coordinates
  Bounds world_bounds;                          // corners of [index_min, index_max] through the map
  Vec3 voxel_size{0.0};
  bool has_value_range = false;  // scalar grids only
  double min_value = 0, max_value = 0, mean_active = 0;
};

// Lists every grid of a .vdb or .nvdb file. Errors (nimbus::Error) name the file.
std::vector<GridInfo> inspect_volume_file(const std::filesystem::path& file);

}  // namespace nimbus
