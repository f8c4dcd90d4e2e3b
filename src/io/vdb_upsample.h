// Upsampling an OpenVDB float grid by an integer factor per axis (nimbus convert --upsample N): the
// same density field on a finer lattice, for the large-volume study of docs/benchmarks.md. Not a public
// header: it includes OpenVDB, so only the OpenVDB side of the volume reader (vdb_openvdb.cpp) uses it.
#pragma once

#include <openvdb/openvdb.h>

#include <cstdint>
#include <string>

namespace nimbus::detail {

// The largest upsampling factor accepted (per axis): 16^3 = 4096 times the voxels.
inline constexpr int kMaxUpsample = 16;

// The voxels of the index bbox of `grid`'s values (active voxels and tiles, and inactive leaf voxels,
// which the sampler reads too), dilated by one voxel, once upsampled by `factor` per axis: what
// upsample_float_grid may fill at most. The caller checks it against what the renderer accepts.
uint64_t upsampled_bbox_voxels(const openvdb::FloatGrid& grid, int factor);

// The grid upsampled by `factor` (1 ... kMaxUpsample) per axis. The new grid's map is the old one with
// index coordinates divided by `factor` first (fine voxel i sits at coarse index i / factor, the same
// world point), and its value at fine voxel i is the trilinear interpolation of the old voxel values
// (negative values clamped to 0, as media/density_grid.h samples) at coarse index i / factor. Because
// the old field is trilinear in each coarse cell and each fine cell lies inside one coarse cell, the
// new grid sampled trilinearly is the same field as the old one (up to float rounding). Fine voxels
// whose value is 0 stay inactive background; the rest are active; uniform leaves are then pruned to
// tiles. Name, class and metadata are kept.
openvdb::FloatGrid::Ptr upsample_float_grid(const openvdb::FloatGrid& grid, int factor);

}  // namespace nimbus::detail
