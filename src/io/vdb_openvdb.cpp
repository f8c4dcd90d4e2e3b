// Volume files, OpenVDB side: with vdb_upsample.cpp and vdb_openvdb_dense.cpp, the only code of the library that includes OpenVDB (it
// compiles slowly). Built into the module libnimbus_openvdb.so, or linked in (io/vdb_internal.h says when).
// Reads .vdb grids, converts float grids to NanoVDB once, and lists grids for `nimbus info`.
// Every OpenVDB exception (and bad_alloc from a corrupt size field) becomes a nimbus::Error naming the file.
#include <fmt/format.h>
#include <nanovdb/util/OpenToNanoVDB.h>
#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <mutex>
#include <sstream>

#include "io/vdb_internal.h"
#include "io/vdb_upsample.h"
#include "nimbus/error.h"

namespace nimbus::detail {

namespace {

void init_openvdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

std::string display_name(const std::string& name) { return name.empty() ? "(unnamed)" : "\"" + name + "\""; }

// A light pre-check of the OpenVDB file layout before OpenVDB reads it: OpenVDB trusts every length
// and count field, so a flipped bit in one can make it allocate and zero gigabytes (tens of seconds)
// before failing. Checks the header, the file metadata, the grid descriptors and each grid's own
// metadata: every string, value and count must fit in the bytes that remain, every offset in the file.
class LayoutCheck {
 public:
  LayoutCheck(const std::filesystem::path& path, std::vector<char> bytes)
      : path_(path), b_(std::move(bytes)) {}
  void run() {
    u64();  // magic (an int64), checked by the caller
    const uint32_t version = u32();
    if (version < 213 || version > 1000) bad(fmt::format("unsupported OpenVDB file version {}", version));
    u32(), u32();  // library version
    const bool offsets = u8() != 0;
    if (version < 222) u32();  // per-file compression flags (older files)
    skip(36, "file UUID");
    meta_map("file metadata");
    const uint32_t grids = u32();
    if (grids > (b_.size() - pos_) / 36) bad(fmt::format("grid count {} exceeds the file", grids));
    if (!offsets) {
      // A streamed file (io::Stream writes no grid offsets): each descriptor follows the previous
      // grid's data, whose length is unknown here. io::Stream reads the first one before any grid
      // data, so check its strings (a corrupt name length cost 860 MB from a 5 KB file; found by
      // fuzz/vdb_fuzz.cpp, tests/io/fuzz_regression_test.cpp).
      if (grids > 0) {
        str("grid name"), str("grid type");
        if (version >= 216) str("instance parent");
      }
      return;
    }
    std::vector<uint64_t> grid_pos;
    for (uint32_t i = 0; i < grids; ++i) {
      str("grid name"), str("grid type");
      if (version >= 216) str("instance parent");
      const uint64_t gp = u64(), block = u64(), end = u64();
      if (gp > b_.size() || block > b_.size() || end > b_.size() || gp > block || block > end)
        bad(fmt::format("grid {} lies outside the file ({} bytes)", i, b_.size()));
      grid_pos.push_back(gp);
      pos_ = end;  // the next descriptor follows this grid's data
    }
    for (const uint64_t gp : grid_pos) {
      pos_ = gp;
      if (version >= 222) u32();  // compression flags
      meta_map("grid metadata");
      // From version 216 the transform follows; its type name is a length-prefixed string that
      // OpenVDB allocates (and zero-fills) before reading: a corrupt length cost 4 GiB and 5 s
      // (found by fuzz/vdb_fuzz.cpp; tests/io/fuzz_regression_test.cpp).
      if (version >= 216) str("transform type name");
    }
  }

 private:
  [[noreturn]] void bad(const std::string& what) { fail(path_, "corrupt OpenVDB file: " + what); }
  void need(uint64_t n, const char* what) {
    if (n > b_.size() - pos_)
      bad(fmt::format("{} needs {} bytes at byte {}, beyond the end of the file", what, n, pos_));
  }
  void skip(uint64_t n, const char* what) { need(n, what), pos_ += n; }
  template <typename T>
  T get() {
    need(sizeof(T), "a field");
    T v;
    std::memcpy(&v, b_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  uint32_t u32() { return get<uint32_t>(); }
  uint64_t u64() { return get<uint64_t>(); }
  uint8_t u8() { return get<uint8_t>(); }
  void str(const char* what) { skip(u32(), what); }
  void meta_map(const char* what) {
    const uint32_t count = u32();
    if (count > (b_.size() - pos_) / 12) bad(fmt::format("{}: {} entries exceed the file", what, count));
    for (uint32_t i = 0; i < count; ++i) str(what), str(what), skip(u32(), what);
  }
  std::filesystem::path path_;
  std::vector<char> b_;
  uint64_t pos_ = 0;
};

// Reads every grid of an OpenVDB file through io::Stream (not io::File: io::File reads a truncated
// file without complaint, while a stream that runs out of bytes sets failbit), then runs f(grids).
// Library exceptions, and bad_alloc from a corrupt size field, become nimbus::Error.
template <typename F>
auto with_grids(const std::filesystem::path& path, F&& f) {
  init_openvdb();
  try {
    std::ifstream file(path, std::ios::binary);
    if (!file) fail(path, "cannot open for reading");
    std::vector<char> bytes{std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>()};
    LayoutCheck(path, bytes).run();
    std::istringstream is(std::string(bytes.begin(), bytes.end()));
    // A read past the end throws at once: OpenVDB does not check the stream inside its loops, so a
    // corrupt count (of tiles, of leaves) otherwise spins billions of times on a failed stream
    // (found by fuzz/vdb_fuzz.cpp; tests/io/fuzz_regression_test.cpp).
    is.exceptions(std::ios::failbit | std::ios::badbit);
    openvdb::io::Stream stream(is, /*delayLoad=*/false);
    const openvdb::GridPtrVecPtr grids = stream.getGrids();
    if (!is || !grids) fail(path, "truncated or corrupt OpenVDB file (unexpected end of data)");
    return f(*grids);
  } catch (const Error&) {
    throw;
  } catch (const std::ios_base::failure&) {
    fail(path, "truncated or corrupt OpenVDB file (unexpected end of data)");
  } catch (const std::bad_alloc&) {
    fail(path, "corrupt OpenVDB file (a size field asks for more memory than is available)");
  } catch (const std::exception& e) {
    fail(path, fmt::format("cannot read OpenVDB file: {}", e.what()));
  }
}

std::string grid_list(const openvdb::GridPtrVec& grids) {
  std::string list;
  for (const auto& g : grids)
    list += fmt::format("{}{} ({})", list.empty() ? "" : ", ", display_name(g->getName()), g->valueType());
  return list.empty() ? "no grids" : list;
}

}  // namespace

// The root table's keys (origins of 4096^3 nodes and tiles) of a grid of any standard type must lie
// within +-2^30: OpenVDB's bbox evaluation and NanoVDB's converter add node sizes to them in int32, so a
// corrupt key near INT_MAX would overflow.
void check_index_range(const std::filesystem::path& path, const openvdb::GridBase& grid) {
  grid.apply<openvdb::GridTypes>([&](const auto& typed) {
    for (auto it = typed.tree().root().cbeginChildAll(); it; ++it) {
      const openvdb::Coord o = it.getCoord();
      for (int a = 0; a < 3; ++a)
        if (o[a] < -kMaxIndexCoord || o[a] > kMaxIndexCoord - 4096)
          fail(path, fmt::format("grid {} has voxels at index ({}, {}, {}), beyond +-2^30",
                                 display_name(grid.getName()), o[0], o[1], o[2]));
    }
  });
}

// Before upsampling `grid` by `factor`: a factor in [1, kMaxUpsample], fine index coordinates within
// +-2^30, and a fine bbox the renderer accepts (at most 2^31 voxels, media/density_grid.cpp), so a
// too-large request fails at once instead of filling memory.
static void check_upsample(const std::filesystem::path& path, const openvdb::FloatGrid& grid, int factor) {
  const std::string name = display_name(grid.getName());
  if (factor < 1 || factor > kMaxUpsample)
    fail(path, fmt::format("upsampling grid {} by {}: the factor must be an integer in [1, {}]", name, factor,
                           kMaxUpsample));
  const openvdb::CoordBBox bb = grid.evalActiveVoxelBoundingBox();
  for (int a = 0; a < 3; ++a)
    if (std::max(std::abs(int64_t(bb.min()[a]) - 1), std::abs(int64_t(bb.max()[a]) + 1)) * factor >=
        kMaxIndexCoord - 4096)
      fail(path, fmt::format("upsampling grid {} by {} puts voxels beyond index +-2^30", name, factor));
  const uint64_t voxels = upsampled_bbox_voxels(grid, factor);
  if (voxels > (uint64_t(1) << 31))
    fail(path,
         fmt::format("upsampling grid {} by {} gives an index bbox of {:.3g} voxels, more than the 2^31 "
                     "a density grid may hold",
                     name, factor, double(voxels)));
}

static NanoHandle float_grid(const std::filesystem::path& path, const std::string& grid_name, int upsample) {
  return with_grids(path, [&](const openvdb::GridPtrVec& grids) {
    openvdb::GridBase::ConstPtr chosen;
    for (const auto& g : grids) {
      if (grid_name.empty() ? g->isType<openvdb::FloatGrid>() : g->getName() == grid_name) {
        chosen = g;
        break;
      }
    }
    if (!chosen) {
      if (grid_name.empty()) fail(path, "no float grid in the file; it holds " + grid_list(grids));
      fail(path, fmt::format("no grid named \"{}\"; the file holds {}", grid_name, grid_list(grids)));
    }
    if (!chosen->isType<openvdb::FloatGrid>())
      fail(path, fmt::format("grid {} is of type {}, not float", display_name(chosen->getName()),
                             chosen->valueType()));
    const auto grid = openvdb::gridConstPtrCast<openvdb::FloatGrid>(chosen);
    if (!grid) fail(path, "grid is not a float grid");
    if (!grid->transform().isLinear())
      fail(path, fmt::format("grid {} has a non-linear (frustum) transform, which is not supported",
                             display_name(grid->getName())));
    if (grid->tree().activeVoxelCount() == 0)
      fail(path, fmt::format("grid {} is empty: no active voxels", display_name(grid->getName())));
    check_index_range(path, *grid);
    // No stats or checksum: DensityGrid computes what it needs from the converted tree.
    if (upsample == 1)
      return nanovdb::openToNanoVDB<nanovdb::HostBuffer>(*grid, nanovdb::StatsMode::BBox,
                                                         nanovdb::ChecksumMode::Disable);
    check_upsample(path, *grid, upsample);
    return nanovdb::openToNanoVDB<nanovdb::HostBuffer>(
        *upsample_float_grid(*grid, upsample), nanovdb::StatsMode::BBox, nanovdb::ChecksumMode::Disable);
  });
}

static std::array<NanoHandle, 3> vec3_grid(const std::filesystem::path& path, const std::string& grid_name) {
  return with_grids(path, [&](const openvdb::GridPtrVec& grids) {
    openvdb::Vec3SGrid::ConstPtr grid;
    for (const auto& g : grids)
      if (g->getName() == grid_name) grid = openvdb::gridConstPtrCast<openvdb::Vec3SGrid>(g);
    if (!grid) {
      for (const auto& g : grids)
        if (g->getName() == grid_name)
          fail(path,
               fmt::format("grid {} is of type {}, not vec3s", display_name(grid_name), g->valueType()));
      fail(path, fmt::format("no grid named \"{}\"; the file holds {}", grid_name, grid_list(grids)));
    }
    if (!grid->transform().isLinear())
      fail(path, fmt::format("grid {} has a non-linear (frustum) transform, which is not supported",
                             display_name(grid_name)));
    if (grid->tree().activeVoxelCount() == 0)
      fail(path, fmt::format("grid {} is empty: no active voxels", display_name(grid_name)));
    check_index_range(path, *grid);
    // One float grid per component, with the vec3 grid's transform and active values (tiles filled).
    std::array<NanoHandle, 3> out;
    for (int c = 0; c < 3; ++c) {
      auto f = openvdb::FloatGrid::create(0.0f);
      f->setTransform(grid->transform().copy());
      f->setName(grid_name + "." + "xyz"[c]);
      auto acc = f->getAccessor();
      for (auto it = grid->cbeginValueOn(); it; ++it) {
        if (it.isVoxelValue())
          acc.setValue(it.getCoord(), (*it)[c]);
        else
          f->tree().fill(it.getBoundingBox(), (*it)[c], true);
      }
      out[c] = nanovdb::openToNanoVDB<nanovdb::HostBuffer>(*f, nanovdb::StatsMode::BBox,
                                                           nanovdb::ChecksumMode::Disable);
    }
    return out;
  });
}

static std::vector<GridInfo> file_grids(const std::filesystem::path& path) {
  return with_grids(path, [&](const openvdb::GridPtrVec& grids) {
    std::vector<GridInfo> out;
    for (const auto& g : grids) {
      GridInfo gi;
      gi.name = g->getName();
      gi.type = g->valueType();
      gi.grid_class = openvdb::GridBase::gridClassToString(g->getGridClass());
      gi.active_voxels = g->activeVoxelCount();
      gi.tiles = g->baseTree().activeTileCount();
      check_index_range(path, *g);
      const openvdb::CoordBBox bb = g->evalActiveVoxelBoundingBox();
      gi.empty = bb.empty();
      const auto vs = g->voxelSize();
      gi.voxel_size = Vec3(vs[0], vs[1], vs[2]);
      if (!gi.empty) {
        for (int a = 0; a < 3; ++a) gi.index_min[a] = bb.min()[a], gi.index_max[a] = bb.max()[a];
        for (int c = 0; c < 8; ++c) {
          const openvdb::Vec3d p(c & 1 ? bb.max()[0] : bb.min()[0], c & 2 ? bb.max()[1] : bb.min()[1],
                                 c & 4 ? bb.max()[2] : bb.min()[2]);
          const auto q = g->transform().indexToWorld(p);
          gi.world_bounds.extend(Vec3(q[0], q[1], q[2]));
        }
      }
      const auto scalar_range = [&](const auto& grid) {
        double mn = std::numeric_limits<double>::infinity(), mx = -mn, sum = 0;
        uint64_t n = 0;
        for (auto it = grid.cbeginValueOn(); it; ++it) {
          const double v = static_cast<double>(*it);
          const uint64_t count = it.getVoxelCount();
          mn = std::min(mn, v);
          mx = std::max(mx, v);
          sum += v * static_cast<double>(count);
          n += count;
        }
        if (n > 0) gi.has_value_range = true, gi.min_value = mn, gi.max_value = mx, gi.mean_active = sum / n;
      };
      if (auto f = openvdb::gridConstPtrCast<openvdb::FloatGrid>(g))
        scalar_range(*f);
      else if (auto d = openvdb::gridConstPtrCast<openvdb::DoubleGrid>(g))
        scalar_range(*d);
      else if (auto i = openvdb::gridConstPtrCast<openvdb::Int32Grid>(g))
        scalar_range(*i);
      out.push_back(std::move(gi));
    }
    return out;
  });
}

}  // namespace nimbus::detail

// The module's one export (io/vdb_internal.h): the table of the three functions above and of
// vdb_openvdb_dense.cpp's two.
extern "C" __attribute__((visibility("default"))) const nimbus::detail::OpenVdbModule*
nimbus_openvdb_module() {
  static constexpr nimbus::detail::OpenVdbModule table{
      nimbus::detail::kOpenVdbModuleAbi, &nimbus::detail::float_grid,
      &nimbus::detail::vec3_grid,        &nimbus::detail::file_grids,
      &nimbus::detail::dense_to_openvdb, &nimbus::detail::write_openvdb_grid};
  return &table;
}
