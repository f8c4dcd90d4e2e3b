// Shared between the NanoVDB side (vdb.cpp) and the OpenVDB side (vdb_openvdb.cpp) of the volume
// reader. Not a public header.
#pragma once

#include <fmt/format.h>
#include <nanovdb/util/GridHandle.h>
#include <nanovdb/util/HostBuffer.h>

#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "io/vdb.h"
#include "nimbus/error.h"

namespace nimbus::detail {

using NanoHandle = nanovdb::GridHandle<nanovdb::HostBuffer>;

// "<file>: <what>" as a nimbus::Error. Inline: the OpenVDB module (below) holds its own copy.
[[noreturn]] inline void fail(const std::filesystem::path& file, const std::string& what) {
  throw Error(fmt::format("{}: {}", file.string(), what));
}

// The OpenVDB side. libopenvdb costs every process that links it about 0.05 CPU s at start (the dynamic
// linker resolves its 69 000 symbol relocations), so by default it lives in a module of its own,
// libnimbus_openvdb.so, loaded with dlopen when the first .vdb file is read (io/vdb_openvdb_loader.cpp);
// .nvdb files and scenes without volume files never load it. Programs that use OpenVDB themselves (the
// tests, the Python module) and the sanitizer builds link it in (CMakeLists.txt, NIMBUS_LAZY_OPENVDB).
//
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

// A volume made in memory (nimbus.Volume from a numpy array): values[i][j][k] (z fastest) of voxel
// (i, j, k) + index_offset; world = origin + voxel_size * index. active: null (the non-zero voxels are
// active) or a mask of the same layout.
struct DenseVolume {
  const float* values = nullptr;
  std::array<int, 3> shape{};
  std::array<double, 3> voxel_size{}, origin{};
  std::array<int, 3> index_offset{};
  std::string name;
  const bool* active = nullptr;
};
// Its OpenVDB float grid (a fog volume, 0 background, to keep for writing it out) and that grid converted
// to NanoVDB as a .vdb file's grid is (no NanoVDB grid when no voxel is active).
struct DenseGrid {
  std::shared_ptr<void> grid;  // the openvdb::FloatGrid
  NanoHandle nano;
  uint64_t active_voxels = 0;
};
DenseGrid openvdb_grid_from_dense(const DenseVolume& volume);
// Writes a DenseGrid's grid as the .vdb file `path` (through `path`.tmp; errors name `path`).
void save_openvdb_grid(const std::shared_ptr<void>& grid, const std::filesystem::path& path);

// The module's side of the five functions above (vdb_openvdb.cpp, vdb_openvdb_dense.cpp), as one table
// (the module exports nothing else: nimbus_openvdb_module()).
struct OpenVdbModule {
  int abi;  // kOpenVdbModuleAbi of the build that made it
  NanoHandle (*load_float_grid)(const std::filesystem::path&, const std::string&, int);
  std::array<NanoHandle, 3> (*load_vec3_grid)(const std::filesystem::path&, const std::string&);
  std::vector<GridInfo> (*inspect_file)(const std::filesystem::path&);
  DenseGrid (*grid_from_dense)(const DenseVolume&);
  void (*save_grid)(const std::shared_ptr<void>&, const std::filesystem::path&);
};
// Raised whenever OpenVdbModule or the types it passes change shape.
inline constexpr int kOpenVdbModuleAbi = 2;
DenseGrid dense_to_openvdb(const DenseVolume& volume);
void write_openvdb_grid(const std::shared_ptr<void>& grid, const std::filesystem::path& path);

// Voxel index coordinates must lie in [-2^30, 2^30): far inside int32, so node and bbox arithmetic
// (origin + node size, max + 1) cannot overflow.
inline constexpr int kMaxIndexCoord = 1 << 30;

}  // namespace nimbus::detail
