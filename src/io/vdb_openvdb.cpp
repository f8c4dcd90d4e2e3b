// Volume files, OpenVDB side: the only translation unit that includes OpenVDB (it compiles slowly).
// Reads .vdb grids, converts float grids to NanoVDB once, and lists grids for `nimbus info`.
// Every OpenVDB exception (and bad_alloc from a corrupt size field) becomes a nimbus::Error naming the file.
#include <fmt/format.h>
#include <nanovdb/util/OpenToNanoVDB.h>
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

#include <mutex>

#include "io/vdb_internal.h"
#include "nimbus/error.h"

namespace nimbus::detail {

namespace {

void init_openvdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

std::string display_name(const std::string& name) { return name.empty() ? "(unnamed)" : "\"" + name + "\""; }

// Runs f(file) with an open OpenVDB file, turning library exceptions into nimbus::Error.
template <typename F>
auto with_file(const std::filesystem::path& path, F&& f) {
  init_openvdb();
  try {
    openvdb::io::File file(path.string());
    file.open(/*delayLoad=*/false);
    return f(file);
  } catch (const Error&) {
    throw;
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

NanoHandle load_openvdb_float_grid(const std::filesystem::path& path, const std::string& grid_name) {
  return with_file(path, [&](openvdb::io::File& file) {
    const openvdb::GridPtrVecPtr metas = file.readAllGridMetadata();
    openvdb::GridBase::ConstPtr chosen;
    for (const auto& g : *metas) {
      if (grid_name.empty() ? g->isType<openvdb::FloatGrid>() : g->getName() == grid_name) {
        chosen = g;
        break;
      }
    }
    if (!chosen) {
      if (grid_name.empty()) fail(path, "no float grid in the file; it holds " + grid_list(*metas));
      fail(path, fmt::format("no grid named \"{}\"; the file holds {}", grid_name, grid_list(*metas)));
    }
    if (!chosen->isType<openvdb::FloatGrid>())
      fail(path, fmt::format("grid {} is of type {}, not float", display_name(chosen->getName()),
                             chosen->valueType()));
    const auto base = file.readGrid(chosen->getName());
    const auto grid = openvdb::gridConstPtrCast<openvdb::FloatGrid>(base);
    if (!grid) fail(path, "grid is not a float grid");
    if (!grid->transform().isLinear())
      fail(path, fmt::format("grid {} has a non-linear (frustum) transform, which is not supported",
                             display_name(grid->getName())));
    // No stats or checksum: DensityGrid computes what it needs from the converted tree.
    return nanovdb::openToNanoVDB<nanovdb::HostBuffer>(*grid, nanovdb::StatsMode::BBox,
                                                       nanovdb::ChecksumMode::Disable);
  });
}

std::vector<GridInfo> inspect_openvdb_file(const std::filesystem::path& path) {
  return with_file(path, [&](openvdb::io::File& file) {
    const openvdb::GridPtrVecPtr grids = file.getGrids();
    std::vector<GridInfo> out;
    for (const auto& g : *grids) {
      GridInfo gi;
      gi.name = g->getName();
      gi.type = g->valueType();
      gi.grid_class = openvdb::GridBase::gridClassToString(g->getGridClass());
      gi.active_voxels = g->activeVoxelCount();
      gi.tiles = g->baseTree().activeTileCount();
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
