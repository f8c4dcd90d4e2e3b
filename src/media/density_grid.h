// The runtime density grid: a scalar NanoVDB float grid in memory, sampled with trilinear
// interpolation in index space, with a coarse "brick max" array for cheap conservative majorants, its
// statistics and its index <-> world maps. Reading volume files (OpenVDB, .nvdb) is io/vdb.h's.
//
// A grid whose data bbox is small also keeps a dense copy of the voxels the sampler can read (see
// kDenseMaxBytes): its lookups read that array instead of descending the tree, with the same values and
// the same arithmetic, so the density is bit for bit the same (issue 12).
//
// Conventions (NanoVDB/OpenVDB): the value of voxel ijk sits at the index-space point (i, j, k);
// index <-> world is the grid's own affine map. Negative voxel values are clamped to 0 before
// interpolation (their count is reported in stats().negative_count); NaN/inf values anywhere the
// sampler can read them are an error. Every error is a nimbus::Error that names the grid's source.
#pragma once

#include <nanovdb/NanoVDB.h>
#include <nanovdb/util/GridHandle.h>
#include <nanovdb/util/HostBuffer.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>

#include "core/math.h"

namespace nimbus {

// What one walk over a float grid's tree finds (the active values, counting an active tile by the
// voxels it covers). The grid must be structurally sound: built in memory, or checked by io/vdb.h.
struct GridSummary {
  uint64_t active_voxels = 0, tiles = 0;
  nanovdb::CoordBBox bbox;  // of the active values; empty if none
  std::string name;         // the grid's name
  double min = std::numeric_limits<double>::infinity(), max = -min, sum = 0;  // over the active values (raw)
};
// Walks the tree in storage order (root tiles, then each upper, lower and leaf node's table).
GridSummary summarize_float_grid(const nanovdb::FloatGrid& grid);

class DensityGrid {
 public:
  struct Stats {
    std::string name;            // grid name ("" for an unnamed grid)
    std::string file;            // the file it came from
    uint64_t active_voxels = 0;  // active voxels, counting active tiles by the voxels they cover
    uint64_t tiles = 0;          // active tiles (root, upper and lower internal nodes)
    Vec3 voxel_size{0.0};        // world units
    std::array<int, 3> index_min{}, index_max{};           // active index bbox (inclusive voxel coordinates)
    double min_value = 0, max_value = 0, mean_active = 0;  // over the active values (raw, unclamped)
    uint64_t negative_count = 0;  // voxels with a negative value that sampling can read (clamped to 0)
    uint64_t dense_bytes = 0;     // bytes of the dense copy of the voxels (0: none; see kDenseMaxBytes)
    double read_seconds = 0;      // wall time to read (and for .vdb convert) the grid
    double analyse_seconds = 0;   // wall time of the checks, statistics and brick max build
  };

  // A per-thread sampler: holds a NanoVDB ReadAccessor (which caches the last nodes visited and is
  // not thread-safe) for a grid without a dense copy; with one it reads the copy, as density_index does.
  // Cheap to create (see bench/bench_vdb.cpp). The grid must outlive it.
  class Sampler {
   public:
    explicit Sampler(const DensityGrid& grid) : grid_(&grid), acc_(grid.grid_->getAccessor()) {}
    double density_index(const Vec3& index_pos) {
      return grid_->dense_ != nullptr ? grid_->trilinear_dense(index_pos) : grid_->trilinear(acc_, index_pos);
    }

   private:
    const DensityGrid* grid_;
    nanovdb::DefaultReadAccessor<float> acc_;
  };

  // Wraps a float grid: one built in memory (e.g. a voxelised procedural shape), or one read from a
  // file whose structure io/vdb.h has checked (load_density_grid). Gathers the statistics, checks the
  // values (no empty grid, a bbox of at most 2^31 voxels, no NaN/inf the sampler can read) and builds
  // the brick max. `source` names the grid in errors ("<source>: <what>"). read_seconds and
  // check_seconds are the caller's time to read and check it, kept in stats().
  //
  // The dense copy: when the voxels the sampler can read (the data bbox [index_lo, index_hi] plus one
  // voxel above, per axis) take at most kDenseMaxBytes as floats, they are copied into one array (z
  // fastest, as in a NanoVDB leaf; negative values stored as 0) and every lookup reads it. The cap, 64 MiB
  // (16.8 M voxels), is about what the photon grids of `mfs` take: the Disney cloud at 1/16 takes 7.2 MB
  // (4.3 voxels per active voxel), the same upsampled 2x per axis 53 MB; 4x (418 MB) reads the tree.
  // A lookup costs 0.25-0.4 of the tree's (docs/benchmarks.md, "A dense copy of small grids").
  static constexpr uint64_t kDenseMaxBytes = uint64_t(64) << 20;
  static DensityGrid from_nanovdb(nanovdb::GridHandle<nanovdb::HostBuffer> handle, const std::string& source,
                                  double read_seconds = 0.0, double check_seconds = 0.0,
                                  uint64_t dense_max_bytes = kDenseMaxBytes);

  // Index space <-> the grid's world space (the file's own transform). world_to_index: NanoVDB's
  // worldToIndex, inline where the map is axis-aligned (see axis_aligned_).
  Vec3 world_to_index(const Vec3& grid_world) const {
    if (!axis_aligned_) return world_to_index_map(grid_world);
    const double* m = inv_mat_;
    const double x = grid_world.x - vec_[0], y = grid_world.y - vec_[1], z = grid_world.z - vec_[2];
    return {x * m[0] + (y * m[1] + z * m[2]), x * m[3] + (y * m[4] + z * m[5]),
            x * m[6] + (y * m[7] + z * m[8])};
  }
  Vec3 index_to_world(const Vec3& index) const;

  // Trilinear density at an index-space position (negative voxels clamped to 0); 0 outside
  // [index_lo(), index_hi()]. Reads the dense copy when there is one. Otherwise thread-safe: each thread keeps one accessor for the grid it read last
  // (keyed by the grid's process-unique id, not its address), so lookups near the previous one skip the
  // descent from the root (the photons' tracking and the shadow maps' marches: issue 12). The values
  // are the same as with a fresh accessor.
  double density_index(const Vec3& index_pos) const {
    if (dense_ != nullptr) return trilinear_dense(index_pos);
    struct Cache {
      uint64_t id = 0;
      std::optional<nanovdb::DefaultReadAccessor<float>> acc;
    };
    thread_local Cache cache;
    if (cache.id != id_) {
      cache.acc.emplace(grid_->getAccessor());
      cache.id = id_;
    }
    return trilinear(*cache.acc, index_pos);
  }

  // Conservative maximum of density_index over the index-space box [index_lo, index_hi] (corners in any
  // order is not allowed: lo <= hi per axis). Never below any density_index(p), p in the box; 0 for a
  // box outside the data. Reads the brick max array (bricks of 8^3 cells; each holds the max over its
  // voxels dilated by one voxel, times (1 + 1e-6) to absorb rounding).
  double max_density_index(const Vec3& index_lo, const Vec3& index_hi) const;
  // The same from the voxels themselves (those that trilinear reads for a point of the box, negative
  // ones as 0), times (1 + 1e-6): as tight as a bound on the box can be, and slower (one voxel read
  // each; for the photons' own majorant grid, MajorantGrid's `exact`).
  double max_density_index_exact(const Vec3& index_lo, const Vec3& index_hi) const;
  // The maximum density anywhere (the max over all bricks).
  double max_density() const { return max_density_; }

  // Index-space bbox of the data: the active bbox dilated by one voxel. density_index is 0 outside it.
  Vec3 index_lo() const { return lo_; }
  Vec3 index_hi() const { return hi_; }
  // World bounds: the 8 corners of [index_lo, index_hi] through the grid's map.
  Bounds world_bounds() const;

  const Stats& stats() const;
  // Whether lookups read a dense copy of the voxels (see kDenseMaxBytes).
  bool has_dense() const { return dense_ != nullptr; }
  // A copy of this grid (sharing its data) whose lookups read the tree, as if it had no dense copy: the
  // reference for tests and benchmarks of the dense path. stats() still counts the dense copy's bytes.
  DensityGrid without_dense() const {
    DensityGrid g = *this;
    g.dense_ = nullptr;
    return g;
  }
  // The NanoVDB grid itself (for HDDA, tests and GPU upload). Valid while this object (or a copy) lives.
  const nanovdb::FloatGrid& nano_grid() const { return *grid_; }

  // The brick max array (tests and majorant grids): brick (bx, by, bz) covers cells
  // index_lo + 8 * b ... index_lo + 8 * b + 7 (clipped to index_hi).
  std::array<int, 3> brick_counts() const { return brick_n_; }
  float brick_max(int bx, int by, int bz) const {
    return bricks_[(static_cast<size_t>(bz) * brick_n_[1] + by) * brick_n_[0] + bx];
  }

  struct Data;  // owns the NanoVDB buffer, the brick array and the stats (shared by copies)

 private:
  Vec3 world_to_index_map(const Vec3& grid_world) const;  // NanoVDB's Map::applyInverseMap
  template <typename Acc>
  double trilinear(Acc& acc, const Vec3& p) const;
  double trilinear_dense(const Vec3& p) const;
  // The interpolation of the 8 corner values c[dx][dy][dz] (already clamped) at offsets u, v, w: one
  // arithmetic for the tree and the dense copy, so their results are the same bits.
  static double interpolate(const double c[2][2][2], double u, double v, double w) {
    const double c00 = c[0][0][0] + (c[1][0][0] - c[0][0][0]) * u;
    const double c01 = c[0][0][1] + (c[1][0][1] - c[0][0][1]) * u;
    const double c10 = c[0][1][0] + (c[1][1][0] - c[0][1][0]) * u;
    const double c11 = c[0][1][1] + (c[1][1][1] - c[0][1][1]) * u;
    const double c0 = c00 + (c10 - c00) * v;
    const double c1 = c01 + (c11 - c01) * v;
    return c0 + (c1 - c0) * w;
  }

  std::shared_ptr<const Data> data_;
  const nanovdb::FloatGrid* grid_ = nullptr;
  const float* bricks_ = nullptr;
  std::array<int, 3> brick_n_{};
  std::array<int, 3> lo_i_{};  // integer index_lo
  Vec3 lo_{0.0}, hi_{0.0};
  double max_density_ = 0.0;
  // The dense copy (null when none): voxel (i, j, k) at ((i - lo_i_[0]) * dense_sx_ + (j - lo_i_[1]) *
  // dense_sy_ + (k - lo_i_[2])), for i ... index_hi + 1 per axis.
  const float* dense_ = nullptr;
  int64_t dense_sx_ = 0, dense_sy_ = 0;
  uint64_t id_ = 0;  // unique per grid built in this process (copies share it): density_index's cache key
  // The map's inverse and translation (NanoVDB's mInvMatD, mVecD), kept where its off-diagonal entries
  // are all zero (a scale and a translation, as the volume files have). NanoVDB computes row r as
  // fma(x, m[3r], fma(y, m[3r+1], z m[3r+2])); with two of the three products exact signed zeros, the
  // same sums in plain arithmetic are the same number without the library's fma calls (the build targets
  // baseline x86-64, where std::fma is a call). They can differ only in the sign of a zero where the
  // diagonal product underflows; the trilinear lookups take p - floor(p), +0 for either zero, so every
  // density is the same bit for bit (issue 12; tests/media/density_grid_test.cpp).
  bool axis_aligned_ = false;
  double inv_mat_[9] = {}, vec_[3] = {};
};

// ---- inline implementation -------------------------------------------------------------------

template <typename Acc>
inline double DensityGrid::trilinear(Acc& acc, const Vec3& p) const {
  if (!(p.x >= lo_.x && p.y >= lo_.y && p.z >= lo_.z && p.x <= hi_.x && p.y <= hi_.y && p.z <= hi_.z))
    return 0.0;  // also rejects NaN positions
  const double fx = std::floor(p.x), fy = std::floor(p.y), fz = std::floor(p.z);
  const double u = p.x - fx, v = p.y - fy, w = p.z - fz;
  nanovdb::Coord ijk(static_cast<int>(fx), static_cast<int>(fy), static_cast<int>(fz));
  // The 8 corner values (voxels ijk and ijk + 1 per axis), negative ones clamped to 0. Fast path: all
  // eight in one leaf (7 cells in 8 per axis), read straight from the leaf's value array.
  double c[2][2][2];
  const bool one_leaf = (ijk[0] & 7) != 7 && (ijk[1] & 7) != 7 && (ijk[2] & 7) != 7;
  const auto* leaf = one_leaf ? acc.probeLeaf(ijk) : nullptr;
  if (leaf != nullptr) {
    const float* v = leaf->data()->mValues + (((ijk[0] & 7) << 6) | ((ijk[1] & 7) << 3) | (ijk[2] & 7));
    for (int dx = 0; dx < 2; ++dx)
      for (int dy = 0; dy < 2; ++dy)
        for (int dz = 0; dz < 2; ++dz) c[dx][dy][dz] = std::max(0.0f, v[(dx << 6) | (dy << 3) | dz]);
  } else {
    for (int dx = 0; dx < 2; ++dx)
      for (int dy = 0; dy < 2; ++dy)
        for (int dz = 0; dz < 2; ++dz)
          c[dx][dy][dz] = std::max(0.0f, acc.getValue(nanovdb::Coord(ijk[0] + dx, ijk[1] + dy, ijk[2] + dz)));
  }
  return interpolate(c, u, v, w);
}

inline double DensityGrid::trilinear_dense(const Vec3& p) const {
  if (!(p.x >= lo_.x && p.y >= lo_.y && p.z >= lo_.z && p.x <= hi_.x && p.y <= hi_.y && p.z <= hi_.z))
    return 0.0;  // also rejects NaN positions
  const double fx = std::floor(p.x), fy = std::floor(p.y), fz = std::floor(p.z);
  const double u = p.x - fx, v = p.y - fy, w = p.z - fz;
  const float* d =
      dense_ + ((static_cast<int64_t>(fx) - lo_i_[0]) * dense_sx_ +
                (static_cast<int64_t>(fy) - lo_i_[1]) * dense_sy_ + (static_cast<int64_t>(fz) - lo_i_[2]));
  double c[2][2][2];
  for (int dx = 0; dx < 2; ++dx)
    for (int dy = 0; dy < 2; ++dy)
      for (int dz = 0; dz < 2; ++dz) c[dx][dy][dz] = d[dx * dense_sx_ + dy * dense_sy_ + dz];
  return interpolate(c, u, v, w);
}

}  // namespace nimbus
