// OpenVDB to NanoVDB files (nimbus convert IN.vdb OUT.nvdb).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace nimbus {

// Writes the float grids of the OpenVDB file `in` (`grids`: those names; empty: every float grid) as a
// NanoVDB file `out` (ZIP-compressed, full statistics and checksum), atomically. Each grid is read and
// checked as load_density_grid reads a .vdb; `upsample` > 1 refines each by that integer factor per axis
// (io/vdb_upsample.h: the same density field on a lattice `upsample` times finer, for the large-volume
// study of docs/benchmarks.md). Returns the names written. nimbus::Error names the file.
std::vector<std::string> convert_vdb_to_nvdb(const std::filesystem::path& in,
                                             const std::filesystem::path& out,
                                             const std::vector<std::string>& grids = {}, int upsample = 1);

}  // namespace nimbus
