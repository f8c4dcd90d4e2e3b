// Shared between the NanoVDB side (vdb.cpp) and the OpenVDB side (vdb_openvdb.cpp) of the volume
// reader. Not a public header.
#pragma once

#include <nanovdb/util/GridHandle.h>
#include <nanovdb/util/HostBuffer.h>

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include "io/vdb.h"

namespace nimbus::detail {

using NanoHandle = nanovdb::GridHandle<nanovdb::HostBuffer>;

// "<file>: <what>" as a nimbus::Error.
[[noreturn]] void fail(const std::filesystem::path& file, const std::string& what);

// Reads the float grid `grid_name` ("" = the first float grid) of an OpenVDB file and converts it to
// NanoVDB; `upsample` > 1 first refines it by that factor per axis (io/vdb_upsample.h: the same density
// field on a finer lattice). Errors name the file; OpenVDB exceptions are rethrown as nimbus::Error.
NanoHandle load_openvdb_float_grid(const std::filesystem::path& file, const std::string& grid_name,
                                   int upsample = 1);

// The components of the vec3 grid `grid_name` of an OpenVDB file as three float grids (x, y, z).
std::array<NanoHandle, 3> load_openvdb_vec3_grid(const std::filesystem::path& file,
                                                 const std::string& grid_name);

// Every grid of an OpenVDB file, for `nimbus info`.
std::vector<GridInfo> inspect_openvdb_file(const std::filesystem::path& file);

// Voxel index coordinates must lie in [-2^30, 2^30): far inside int32, so node and bbox arithmetic
// (origin + node size, max + 1) cannot overflow.
inline constexpr int kMaxIndexCoord = 1 << 30;

}  // namespace nimbus::detail
