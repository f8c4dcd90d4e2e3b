// The in-memory density grid (media/density_grid.h): the statistics walk over the tree, the checks of
// the values (empty grid, bbox size, NaN/inf), the brick max array and the index <-> world maps.
#include "media/density_grid.h"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstring>
#include <vector>

#include "core/zeroed_floats.h"
#include "nimbus/error.h"

namespace nimbus {

struct DensityGrid::Data {
  nanovdb::GridHandle<nanovdb::HostBuffer> handle;
  std::vector<float> bricks;
  ZeroedFloats dense;  // the dense copy of the voxels (empty: none; huge pages, for the TLB: issue 12)
  DensityGrid::Stats stats;
};

namespace {

using nanovdb::Coord;
using UpperT = nanovdb::NanoUpper<float>;
using LowerT = nanovdb::NanoLower<float>;
using LeafT = nanovdb::NanoLeaf<float>;

// Index bboxes with more voxels than this are rejected (a corrupt file or a grid we cannot brick).
constexpr double kMaxBBoxVoxels = 2147483648.0;  // 2^31

// "<source>: <what>" as a nimbus::Error.
[[noreturn]] void fail(const std::string& source, const std::string& what) {
  throw Error(fmt::format("{}: {}", source, what));
}

// ---- statistics walk ------------------------------------------------------------------------------

// One active value covering the dim^3 voxels from lo.
void add_active(GridSummary& s, double v, uint64_t count, const Coord& lo, int dim) {
  s.active_voxels += count;
  s.min = std::min(s.min, v);
  s.max = std::max(s.max, v);
  s.sum += v * static_cast<double>(count);
  s.bbox.expand(lo);
  s.bbox.expand(lo + Coord(dim - 1));
}

void summarize_lower(GridSummary& s, const LowerT& node, const Coord& o1) {
  const auto* lo = node.data();
  for (uint32_t n1 = 0; n1 < 4096; ++n1) {
    const Coord o0 = o1 + (LowerT::OffsetToLocalCoord(n1) << 3);
    if (!lo->mChildMask.isOn(n1)) {
      if (lo->mValueMask.isOn(n1)) s.tiles++, add_active(s, lo->mTable[n1].value, 512, o0, 8);
      continue;
    }
    const auto* leaf = lo->getChild(n1)->data();
    for (uint32_t n = 0; n < 512; ++n)
      if (leaf->mValueMask.isOn(n)) add_active(s, leaf->mValues[n], 1, o0 + LeafT::OffsetToLocalCoord(n), 1);
  }
}

void summarize_upper(GridSummary& s, const UpperT& node, const Coord& o2) {
  const auto* up = node.data();
  for (uint32_t n2 = 0; n2 < 32768; ++n2) {
    const Coord o1 = o2 + (UpperT::OffsetToLocalCoord(n2) << 7);
    if (!up->mChildMask.isOn(n2)) {
      if (up->mValueMask.isOn(n2)) s.tiles++, add_active(s, up->mTable[n2].value, uint64_t(1) << 21, o1, 128);
      continue;
    }
    summarize_lower(s, *up->getChild(n2), o1);
  }
}

// The grid's name (a short one need not be NUL-terminated in its 256 bytes).
std::string grid_name(const nanovdb::FloatGrid& grid) {
  if (grid.hasLongGridName()) return grid.gridName();
  const char* name = grid.data()->mGridName;
  return std::string(name, strnlen(name, nanovdb::GridData::MaxNameSize));
}

// ---- value checks and brick max -------------------------------------------------------------------

void check_bbox(const std::string& source, const GridSummary& w) {
  if (w.active_voxels == 0) fail(source, "empty grid: no active voxels");
  const auto& b = w.bbox;
  double voxels = 1;
  for (int a = 0; a < 3; ++a) {
    voxels *= static_cast<double>(b.max()[a]) - b.min()[a] + 1.0;
    if (std::abs(b.min()[a]) > (1 << 30) || std::abs(b.max()[a]) > (1 << 30))
      fail(source, "index bbox coordinates beyond +-2^30");
  }
  if (voxels > kMaxBBoxVoxels)
    fail(source,
         fmt::format("index bbox [{}, {}, {}]..[{}, {}, {}] holds {:.3g} voxels (more than 2^31): too large",
                     b.min()[0], b.min()[1], b.min()[2], b.max()[0], b.max()[1], b.max()[2], voxels));
}

// NaN/inf and negative voxels counted by a scan (each voxel once), with the first NaN/inf.
struct ValueCounts {
  uint64_t bad = 0, negative = 0;
  Coord first_bad;
  // n NaN/inf voxels from c; first_bad keeps the smallest c in (x, y, z) order.
  void note_bad(const Coord& c, uint64_t n) {
    const bool less = c[0] != first_bad[0]   ? c[0] < first_bad[0]
                      : c[1] != first_bad[1] ? c[1] < first_bad[1]
                                             : c[2] < first_bad[2];
    if (bad == 0 || less) first_bad = c;
    bad += n;
  }
};

// One brick: cells s ... e per axis; it owns (counts) the voxels s ... own_hi.
struct BrickRange {
  int s[3], e[3], own_hi[3];
};

// The voxels [b0, b1] of a leaf: their max, and the owned ones counted.
float scan_leaf_block(const LeafT& leaf, const int b0[3], const int b1[3], const BrickRange& br,
                      ValueCounts& out) {
  float m = 0.0f;
  for (int i = b0[0]; i <= b1[0]; ++i)
    for (int j = b0[1]; j <= b1[1]; ++j)
      for (int k = b0[2]; k <= b1[2]; ++k) {
        const float v = leaf.getValue(Coord(i, j, k));
        m = std::max(m, v);
        if (i < br.s[0] || j < br.s[1] || k < br.s[2] || i > br.own_hi[0] || j > br.own_hi[1] ||
            k > br.own_hi[2])
          continue;
        if (!std::isfinite(v)) {
          out.note_bad(Coord(i, j, k), 1);
        } else if (v < 0.0f) {
          out.negative++;
        }
      }
  return m;
}

// The voxels [b0, b1] of a block without a leaf: one tile or background value v, counted once per
// owned voxel.
void count_tile_block(float v, const int b0[3], const int b1[3], const BrickRange& br, ValueCounts& out) {
  uint64_t n = 1;
  int c0[3];
  for (int a = 0; a < 3; ++a) {
    c0[a] = std::max(b0[a], br.s[a]);
    const int c1 = std::min(b1[a], br.own_hi[a]);
    n = c1 < c0[a] ? 0 : n * static_cast<uint64_t>(c1 - c0[a] + 1);
  }
  if (n == 0) return;
  if (!std::isfinite(v)) {
    out.note_bad(Coord(c0[0], c0[1], c0[2]), n);
  } else if (v < 0.0f) {
    out.negative += n;
  }
}

// The max over the voxels s - 1 ... e + 1 per axis (what the sampler reads in the brick's cells),
// one leaf-sized block (8^3, aligned) at a time: a block with a leaf is read voxel by voxel; a block
// without one holds a single tile or background value, read once. So the cost follows the data, not
// the empty space in the bbox (a sparse 300 KB file whose bbox holds 2^31 voxels took minutes; found by
// fuzz/vdb_fuzz.cpp). The same pass counts the owned voxels' NaN/inf and negative values.
template <typename Acc>
float scan_brick(Acc& acc, const BrickRange& br, ValueCounts& out) {
  float m = 0.0f;
  const int r0[3] = {br.s[0] - 1, br.s[1] - 1, br.s[2] - 1}, r1[3] = {br.e[0] + 1, br.e[1] + 1, br.e[2] + 1};
  for (int ox = r0[0] & ~7; ox <= r1[0]; ox += 8)
    for (int oy = r0[1] & ~7; oy <= r1[1]; oy += 8)
      for (int oz = r0[2] & ~7; oz <= r1[2]; oz += 8) {
        const int o[3] = {ox, oy, oz};
        int b0[3], b1[3];
        for (int a = 0; a < 3; ++a) b0[a] = std::max(o[a], r0[a]), b1[a] = std::min(o[a] + 7, r1[a]);
        if (const auto* leaf = acc.probeLeaf(Coord(ox, oy, oz))) {
          m = std::max(m, scan_leaf_block(*leaf, b0, b1, br, out));
          continue;
        }
        const float v = acc.getValue(Coord(ox, oy, oz));
        m = std::max(m, v);
        count_tile_block(v, b0, b1, br, out);
      }
  return m;
}

// Fills the brick max array (bricks of 8^3 cells from lo_i, n per axis; cells up to hi_i): each brick
// holds the max over every voxel the sampler can read in its cells (cells [lo, hi] and their +1
// neighbours), dilated by one voxel, times (1 + 1e-6). Counts NaN/inf and negative values, each voxel
// once (in the brick whose cells hold it; the last brick per axis also owns voxel hi + 1).
ValueCounts build_brick_max(const nanovdb::FloatGrid& grid, const std::array<int, 3>& lo_i, const int hi_i[3],
                            const std::array<int, 3>& brick_n, std::vector<float>& bricks) {
  const int nx = brick_n[0], ny = brick_n[1], nz = brick_n[2];
  bricks.assign(static_cast<size_t>(nx) * ny * nz, 0.0f);
  std::vector<ValueCounts> rows(static_cast<size_t>(ny) * nz);
  tbb::parallel_for(tbb::blocked_range<int>(0, ny * nz), [&](const tbb::blocked_range<int>& r) {
    auto acc = grid.getAccessor();
    for (int row = r.begin(); row < r.end(); ++row) {
      const int by = row % ny, bz = row / ny;
      ValueCounts& out = rows[row];
      for (int bx = 0; bx < nx; ++bx) {
        const int b[3] = {bx, by, bz};
        BrickRange br;
        for (int a = 0; a < 3; ++a) {
          br.s[a] = lo_i[a] + 8 * b[a];
          br.e[a] = std::min(br.s[a] + 7, hi_i[a]);
          br.own_hi[a] = br.s[a] + 7 < hi_i[a] ? br.s[a] + 7 : hi_i[a] + 1;
        }
        ValueCounts brick;
        const float m = scan_brick(acc, br, brick);
        if (brick.bad > 0 && out.bad == 0) out.first_bad = brick.first_bad;
        out.bad += brick.bad;
        out.negative += brick.negative;
        bricks[(static_cast<size_t>(bz) * ny + by) * nx + bx] = static_cast<float>(m * (1.0 + 1e-6));
      }
    }
  });
  ValueCounts total;
  for (const ValueCounts& row : rows) {
    if (row.bad > 0 && total.bad == 0) total.first_bad = row.first_bad;
    total.bad += row.bad;
    total.negative += row.negative;
  }
  return total;
}

// ---- dense copy ---------------------------------------------------------------------------------

// Copies the voxels lo ... lo + n - 1 (per axis) into dense (z fastest, then y, then x), negative values
// as 0 (the same std::max(0.0f, v) as the tree sampler). One leaf-sized block (8^3, aligned) at a time:
// a leaf's values are copied from its array; a block without a leaf holds one tile or background value.
// Parallel over x slabs of 8.
void build_dense(const nanovdb::FloatGrid& grid, const std::array<int, 3>& lo, const std::array<int, 3>& n,
                 ZeroedFloats& dense) {
  const int64_t sy = n[2], sx = static_cast<int64_t>(n[1]) * n[2];
  dense = ZeroedFloats(static_cast<size_t>(sx) * n[0]);
  const int x_end = lo[0] + n[0], y_end = lo[1] + n[1], z_end = lo[2] + n[2];
  const int ox0 = lo[0] & ~7, slabs = ((x_end - 1 - ox0) >> 3) + 1;
  tbb::parallel_for(tbb::blocked_range<int>(0, slabs), [&](const tbb::blocked_range<int>& r) {
    auto acc = grid.getAccessor();
    for (int slab = r.begin(); slab < r.end(); ++slab) {
      const int ox = ox0 + 8 * slab;
      for (int oy = lo[1] & ~7; oy < y_end; oy += 8)
        for (int oz = lo[2] & ~7; oz < z_end; oz += 8) {
          const int x0 = std::max(ox, lo[0]), x1 = std::min(ox + 8, x_end);
          const int y0 = std::max(oy, lo[1]), y1 = std::min(oy + 8, y_end);
          const int z0 = std::max(oz, lo[2]), z1 = std::min(oz + 8, z_end);
          const auto* leaf = acc.probeLeaf(Coord(ox, oy, oz));
          const float tile = leaf == nullptr ? std::max(0.0f, acc.getValue(Coord(ox, oy, oz))) : 0.0f;
          for (int x = x0; x < x1; ++x)
            for (int y = y0; y < y1; ++y) {
              float* out = dense.data() + (x - lo[0]) * sx + (y - lo[1]) * sy - lo[2];
              if (leaf == nullptr) {
                std::fill(out + z0, out + z1, tile);
                continue;
              }
              const float* in = leaf->data()->mValues + (((x & 7) << 6) | ((y & 7) << 3));
              for (int z = z0; z < z1; ++z) out[z] = std::max(0.0f, in[z & 7]);
            }
        }
    }
  });
}

void check_finite(const std::string& source, const nanovdb::FloatGrid& grid, const ValueCounts& counts) {
  if (counts.bad == 0) return;
  const Coord& c = counts.first_bad;
  const auto wp = grid.indexToWorld(nanovdb::Vec3d(c[0], c[1], c[2]));
  fail(source,
       fmt::format("{} NaN/inf density values (first at index [{}, {}, {}], world ({:.6g}, {:.6g}, {:.6g}))",
                   counts.bad, c[0], c[1], c[2], wp[0], wp[1], wp[2]));
}

// The grid in a handle, which must hold a float grid.
const nanovdb::FloatGrid* float_grid(const nanovdb::GridHandle<nanovdb::HostBuffer>& handle,
                                     const std::string& source) {
  if (handle.data() == nullptr || handle.size() < sizeof(nanovdb::GridData) ||
      reinterpret_cast<const nanovdb::GridData*>(handle.data())->mGridType != nanovdb::GridType::Float)
    fail(source, "not a float grid");
  // Not GridHandle::grid<float>(): that follows the header's grid index (a grid read alone from a
  // multi-grid file keeps its index).
  return reinterpret_cast<const nanovdb::FloatGrid*>(handle.data());
}

}  // namespace

GridSummary summarize_float_grid(const nanovdb::FloatGrid& grid) {
  GridSummary s;
  const auto* root = grid.tree().root().data();
  for (uint32_t t = 0; t < root->mTableSize; ++t) {
    const auto* tile = root->tile(t);
    const Coord o2 = tile->origin();
    if (!tile->isChild()) {
      if (tile->state) s.tiles++, add_active(s, tile->value, uint64_t(1) << 36, o2, 4096);
      continue;
    }
    summarize_upper(s, *root->getChild(tile), o2);
  }
  s.name = grid_name(grid);
  return s;
}

// ---- DensityGrid ----------------------------------------------------------------------------------

DensityGrid DensityGrid::from_nanovdb(nanovdb::GridHandle<nanovdb::HostBuffer> handle,
                                      const std::string& source, double read_seconds, double check_seconds,
                                      uint64_t dense_max_bytes) {
  const auto t1 = std::chrono::steady_clock::now();
  auto data = std::make_shared<Data>();
  data->handle = std::move(handle);
  const auto* grid = float_grid(data->handle, source);
  const GridSummary w = summarize_float_grid(*grid);
  check_bbox(source, w);

  DensityGrid g;
  g.grid_ = grid;
  static std::atomic<uint64_t> next_id{1};
  g.id_ = next_id.fetch_add(1);
  const nanovdb::Map& map = grid->map();
  const double* inv = map.mInvMatD;
  g.axis_aligned_ =
      inv[1] == 0.0 && inv[2] == 0.0 && inv[3] == 0.0 && inv[5] == 0.0 && inv[6] == 0.0 && inv[7] == 0.0;
  for (int k = 0; k < 9; ++k) g.inv_mat_[k] = inv[k];
  for (int a = 0; a < 3; ++a) g.vec_[a] = map.mVecD[a];
  int hi_i[3];
  for (int a = 0; a < 3; ++a) {
    g.lo_i_[a] = w.bbox.min()[a] - 1;
    g.lo_[a] = g.lo_i_[a];
    g.hi_[a] = w.bbox.max()[a] + 1;
    g.brick_n_[a] = ((w.bbox.max()[a] + 1 - g.lo_i_[a]) >> 3) + 1;
    hi_i[a] = w.bbox.max()[a] + 1;
  }
  const ValueCounts counts = build_brick_max(*grid, g.lo_i_, hi_i, g.brick_n_, data->bricks);
  check_finite(source, *grid, counts);

  // The dense copy: voxels lo_i ... hi_i + 1 per axis (what trilinear reads), if they fit the cap.
  std::array<int, 3> dense_n;
  double dense_bytes = sizeof(float);
  for (int a = 0; a < 3; ++a) dense_n[a] = hi_i[a] + 2 - g.lo_i_[a], dense_bytes *= dense_n[a];
  if (dense_bytes <= static_cast<double>(dense_max_bytes)) {
    build_dense(*grid, g.lo_i_, dense_n, data->dense);
    g.dense_ = data->dense.data();
    g.dense_sy_ = dense_n[2];
    g.dense_sx_ = static_cast<int64_t>(dense_n[1]) * dense_n[2];
  }

  Stats& st = data->stats;
  st.name = w.name;
  st.file = source;
  st.active_voxels = w.active_voxels;
  st.tiles = w.tiles;
  st.voxel_size = Vec3(grid->voxelSize()[0], grid->voxelSize()[1], grid->voxelSize()[2]);
  for (int a = 0; a < 3; ++a) st.index_min[a] = w.bbox.min()[a], st.index_max[a] = w.bbox.max()[a];
  st.min_value = w.min;
  st.max_value = w.max;
  st.mean_active = w.sum / static_cast<double>(w.active_voxels);
  st.negative_count = counts.negative;
  st.dense_bytes = data->dense.size() * sizeof(float);
  st.read_seconds = read_seconds;
  st.analyse_seconds =
      check_seconds + std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
  g.max_density_ = *std::max_element(data->bricks.begin(), data->bricks.end());
  g.bricks_ = data->bricks.data();
  g.data_ = std::move(data);
  return g;
}

Vec3 DensityGrid::world_to_index_map(const Vec3& p) const {
  const auto q = grid_->worldToIndex(nanovdb::Vec3d(p.x, p.y, p.z));
  return {q[0], q[1], q[2]};
}

Vec3 DensityGrid::index_to_world(const Vec3& p) const {
  const auto q = grid_->indexToWorld(nanovdb::Vec3d(p.x, p.y, p.z));
  return {q[0], q[1], q[2]};
}

Bounds DensityGrid::world_bounds() const {
  Bounds b;
  for (int c = 0; c < 8; ++c)
    b.extend(index_to_world({c & 1 ? hi_.x : lo_.x, c & 2 ? hi_.y : lo_.y, c & 4 ? hi_.z : lo_.z}));
  return b;
}

const DensityGrid::Stats& DensityGrid::stats() const { return data_->stats; }

double DensityGrid::max_density_index_exact(const Vec3& a, const Vec3& b) const {
  // A point p reads voxels floor(p) and floor(p) + 1 per axis (trilinear); clipped as above.
  int v0[3], v1[3];
  for (int i = 0; i < 3; ++i) {
    const double l = std::max(a[i], lo_[i]), h = std::min(b[i], hi_[i]);
    if (!(l <= h)) return 0.0;
    v0[i] = static_cast<int>(std::floor(l));
    v1[i] = static_cast<int>(std::floor(h)) + 1;
  }
  auto acc = grid_->getAccessor();
  float m = 0.0f;
  for (int x = v0[0]; x <= v1[0]; ++x)
    for (int y = v0[1]; y <= v1[1]; ++y)
      for (int z = v0[2]; z <= v1[2]; ++z) m = std::max(m, acc.getValue(nanovdb::Coord(x, y, z)));
  return double(m) * (1.0 + 1e-6);
}

double DensityGrid::max_density_index(const Vec3& a, const Vec3& b) const {
  // Cells touched by the box, clipped to [lo, hi]; a point p in cell c reads voxels c and c + 1,
  // which the dilated brick max of c's brick covers.
  int b0[3], b1[3];
  for (int i = 0; i < 3; ++i) {
    const double l = std::max(a[i], lo_[i]), h = std::min(b[i], hi_[i]);
    if (!(l <= h)) return 0.0;
    b0[i] = std::min((static_cast<int>(std::floor(l)) - lo_i_[i]) >> 3, brick_n_[i] - 1);
    b1[i] = std::min((static_cast<int>(std::floor(h)) - lo_i_[i]) >> 3, brick_n_[i] - 1);
  }
  float m = 0.0f;
  for (int z = b0[2]; z <= b1[2]; ++z)
    for (int y = b0[1]; y <= b1[1]; ++y) {
      const float* row = bricks_ + (static_cast<size_t>(z) * brick_n_[1] + y) * brick_n_[0];
      for (int x = b0[0]; x <= b1[0]; ++x) m = std::max(m, row[x]);
    }
  return m;
}

}  // namespace nimbus
