// Upsampling an OpenVDB float grid by an integer factor per axis (io/vdb_upsample.h): trilinear values of
// the coarse grid written on the fine lattice, only where the coarse field can be non-zero.
#include "io/vdb_upsample.h"

#include <openvdb/tools/Morphology.h>
#include <openvdb/tools/Prune.h>

#include <algorithm>

namespace nimbus::detail {

namespace {

// The index box the renderer samples: the active bbox dilated by one voxel (media/density_grid.h).
openvdb::CoordBBox sampled_bbox(const openvdb::FloatGrid& grid) {
  openvdb::CoordBBox bb = grid.evalActiveVoxelBoundingBox();
  if (!bb.empty()) bb.expand(1);
  return bb;
}

// Coarse cells [c, c + 1]^3 that can hold a non-zero value: the voxels with a positive value (active or
// not, tiles as the voxels they cover) inside `bb`, dilated by one voxel across faces, edges and corners
// (a cell is non-zero only if one of its 8 corners is).
openvdb::MaskGrid::Ptr nonzero_cells(const openvdb::FloatGrid& grid, const openvdb::CoordBBox& bb) {
  auto mask = openvdb::MaskGrid::create();
  auto acc = mask->getAccessor();
  for (auto it = grid.tree().cbeginValueAll(); it; ++it) {
    if (!(*it > 0.0f)) continue;
    if (it.isVoxelValue()) {
      if (bb.isInside(it.getCoord())) acc.setValueOn(it.getCoord());
      continue;
    }
    openvdb::CoordBBox tile = it.getBoundingBox();
    tile.intersect(bb);
    if (!tile.empty()) mask->tree().fill(tile, true, true);
  }
  openvdb::tools::dilateActiveValues(mask->tree(), 1, openvdb::tools::NN_FACE_EDGE_VERTEX,
                                     openvdb::tools::EXPAND_TILES);
  return mask;
}

}  // namespace

uint64_t upsampled_bbox_voxels(const openvdb::FloatGrid& grid, int factor) {
  const openvdb::CoordBBox bb = sampled_bbox(grid);
  if (bb.empty()) return 0;
  double n = 1.0;
  for (int a = 0; a < 3; ++a) n *= double(bb.max()[a] - bb.min()[a]) * factor + 1.0;
  return n >= 1.8e19 ? UINT64_MAX : static_cast<uint64_t>(n);
}

openvdb::FloatGrid::Ptr upsample_float_grid(const openvdb::FloatGrid& grid, int factor) {
  openvdb::FloatGrid::Ptr fine = grid.copyWithNewTree();
  openvdb::math::Transform::Ptr xform = grid.transform().copy();
  xform->preScale(1.0 / factor);  // fine index i -> coarse index i / factor -> world
  fine->setTransform(xform);
  const openvdb::CoordBBox bb = sampled_bbox(grid);
  if (bb.empty()) return fine;
  const openvdb::MaskGrid::Ptr cells = nonzero_cells(grid, bb);
  auto in = grid.getConstAccessor();
  auto out = fine->getAccessor();
  const double inv = 1.0 / factor;
  const auto fill_cell = [&](const openvdb::Coord& c) {
    // The 8 corner values of coarse cell c (negative ones clamped to 0, as the renderer samples).
    float v[2][2][2];
    for (int dx = 0; dx < 2; ++dx)
      for (int dy = 0; dy < 2; ++dy)
        for (int dz = 0; dz < 2; ++dz) v[dx][dy][dz] = std::max(0.0f, in.getValue(c.offsetBy(dx, dy, dz)));
    // Fine voxels factor * c + d, d in [0, factor)^3; none beyond the sampled box's far faces.
    int n[3];
    for (int a = 0; a < 3; ++a) n[a] = c[a] == bb.max()[a] ? 1 : factor;
    for (int i = 0; i < n[0]; ++i)
      for (int j = 0; j < n[1]; ++j)
        for (int k = 0; k < n[2]; ++k) {
          const double u = i * inv, w = j * inv, t = k * inv;
          const double c00 = v[0][0][0] + (v[1][0][0] - v[0][0][0]) * u;
          const double c01 = v[0][0][1] + (v[1][0][1] - v[0][0][1]) * u;
          const double c10 = v[0][1][0] + (v[1][1][0] - v[0][1][0]) * u;
          const double c11 = v[0][1][1] + (v[1][1][1] - v[0][1][1]) * u;
          const double c0 = c00 + (c10 - c00) * w, c1 = c01 + (c11 - c01) * w;
          const float value = static_cast<float>(c0 + (c1 - c0) * t);
          if (value > 0.0f)
            out.setValueOn(openvdb::Coord(c[0] * factor + i, c[1] * factor + j, c[2] * factor + k), value);
        }
  };
  for (auto it = cells->tree().cbeginValueOn(); it; ++it) {
    openvdb::CoordBBox box = it.getBoundingBox();
    box.intersect(bb);
    for (auto c = box.begin(); c; ++c) fill_cell(*c);
  }
  openvdb::tools::prune(fine->tree(), 0.0f);  // uniform leaves (a cloud's dense core) become tiles
  return fine;
}

}  // namespace nimbus::detail
