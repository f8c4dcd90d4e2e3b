// OpenVDB to NanoVDB files (io/vdb_convert.h): every float grid through the reader's own conversion
// (vdb_openvdb.cpp), then NanoVDB's statistics and checksum, written in one ZIP-compressed file.
#include "io/vdb_convert.h"

#include <fmt/format.h>
#include <nanovdb/util/GridChecksum.h>
#include <nanovdb/util/GridStats.h>
#include <nanovdb/util/IO.h>

#include "io/atomic_file.h"
#include "io/vdb_internal.h"
#include "nimbus/error.h"

namespace nimbus {

std::vector<std::string> convert_vdb_to_nvdb(const std::filesystem::path& in,
                                             const std::filesystem::path& out,
                                             const std::vector<std::string>& grids, int upsample) {
  if (in.extension() != ".vdb") throw Error(fmt::format("{}: not an OpenVDB (.vdb) file", in.string()));
  std::vector<std::string> names = grids;
  if (names.empty())
    for (const GridInfo& g : inspect_volume_file(in))
      if (g.type == "float") names.push_back(g.name);
  if (names.empty()) throw Error(fmt::format("{}: no float grid to convert", in.string()));
  std::vector<detail::NanoHandle> handles;
  for (const std::string& name : names) {
    detail::NanoHandle h = detail::load_openvdb_float_grid(in, name, upsample);
    nanovdb::FloatGrid* grid = h.grid<float>();
    if (!grid)
      throw Error(fmt::format("{}: grid \"{}\" did not convert to a NanoVDB float grid", in.string(), name));
    nanovdb::gridStats(*grid, nanovdb::StatsMode::All);
    nanovdb::updateChecksum(*grid, nanovdb::ChecksumMode::Full);
    handles.push_back(std::move(h));
  }
  atomic_write(out, [&](const std::filesystem::path& tmp) {
    try {
      nanovdb::io::writeGrids<nanovdb::HostBuffer, std::vector>(tmp.string(), handles,
                                                                nanovdb::io::Codec::ZIP);
    } catch (const std::exception& e) {
      throw Error(fmt::format("{}: cannot write NanoVDB: {}", out.string(), e.what()));
    }
  });
  return names;
}

}  // namespace nimbus
