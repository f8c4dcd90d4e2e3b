// Volume files, OpenVDB side, for volumes made in memory (python/py_volume.cpp: nimbus.Volume from a numpy
// array): the dense values become an OpenVDB float grid, converted once to NanoVDB as a .vdb file's grid is
// (vdb_openvdb.cpp), and the grid can be written as a .vdb file. Part of the OpenVDB module, so that
// `import nimbus` does not load OpenVDB until a volume is made from an array.
#include <fmt/format.h>
#include <nanovdb/util/OpenToNanoVDB.h>
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Dense.h>

#include <filesystem>
#include <memory>
#include <mutex>
#include <system_error>

#include "io/vdb_internal.h"
#include "nimbus/error.h"

namespace nimbus::detail {

namespace {

void init_openvdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

// Voxel activity from a mask of the array's shape (values kept: an inactive voxel still holds its value).
void apply_active_mask(openvdb::FloatGrid& grid, const DenseVolume& d) {
  auto acc = grid.getAccessor();
  const bool* m = d.active;
  for (int i = 0; i < d.shape[0]; ++i)
    for (int j = 0; j < d.shape[1]; ++j)
      for (int k = 0; k < d.shape[2]; ++k) {
        const openvdb::Coord ijk(d.index_offset[0] + i, d.index_offset[1] + j, d.index_offset[2] + k);
        if (*m++ != acc.isValueOn(ijk)) acc.setActiveState(ijk, m[-1]);
      }
}

}  // namespace

// The OpenVDB grid of the array: voxel (i, j, k) of the index space is values[i - i0, j - j0, k - k0] for
// the index offset (i0, j0, k0); index to world is the scale by the voxel size, then the translation.
DenseGrid dense_to_openvdb(const DenseVolume& d) {
  init_openvdb();
  const openvdb::Coord lo(d.index_offset[0], d.index_offset[1], d.index_offset[2]);
  const openvdb::Coord hi(d.index_offset[0] + d.shape[0] - 1, d.index_offset[1] + d.shape[1] - 1,
                          d.index_offset[2] + d.shape[2] - 1);
  // LayoutZYX: z varies fastest, as in a C-ordered array indexed [x, y, z].
  // Only read (copyFromDense), though Dense takes a mutable pointer.
  openvdb::tools::Dense<float, openvdb::tools::LayoutZYX> dense(openvdb::CoordBBox(lo, hi),
                                                                const_cast<float*>(d.values));
  auto grid = openvdb::FloatGrid::create(0.0f);
  openvdb::math::Transform::Ptr xform;
  const std::array<double, 3>& vs = d.voxel_size;
  if (vs[0] == vs[1] && vs[1] == vs[2]) {
    xform = openvdb::math::Transform::createLinearTransform(vs[0]);
  } else {
    openvdb::math::Mat4d m = openvdb::math::Mat4d::identity();
    m.preScale(openvdb::math::Vec3d(vs[0], vs[1], vs[2]));
    xform = openvdb::math::Transform::createLinearTransform(m);
  }
  xform->postTranslate(openvdb::math::Vec3d(d.origin[0], d.origin[1], d.origin[2]));
  grid->setTransform(xform);
  grid->setName(d.name);
  grid->setGridClass(openvdb::GRID_FOG_VOLUME);
  openvdb::tools::copyFromDense(dense, *grid, 0.0f);
  if (d.active) apply_active_mask(*grid, d);
  DenseGrid out;
  out.active_voxels = grid->activeVoxelCount();
  if (out.active_voxels > 0)
    out.nano = nanovdb::openToNanoVDB<nanovdb::HostBuffer>(*grid, nanovdb::StatsMode::BBox,
                                                           nanovdb::ChecksumMode::Disable);
  out.grid = grid;
  return out;
}

// Writes the grid (from dense_to_openvdb) as `path`, through `path`.tmp: no half-written file.
void write_openvdb_grid(const std::shared_ptr<void>& grid, const std::filesystem::path& path) {
  init_openvdb();
  const auto g = std::static_pointer_cast<openvdb::FloatGrid>(grid);
  std::filesystem::path tmp = path;
  tmp += ".tmp";
  try {
    openvdb::io::File file(tmp.string());
    file.write({g});
    file.close();
    std::filesystem::rename(tmp, path);
  } catch (const std::exception& e) {
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    throw Error(fmt::format("{}: cannot write: {}", path.string(), e.what()));
  }
}

}  // namespace nimbus::detail
