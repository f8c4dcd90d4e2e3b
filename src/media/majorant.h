// The majorant grid: a coarse grid over the media's bounds holding, per cell, a scalar bound on the
// extinction of every channel (sum over media of max_channel(sigma_t) x the medium's maximal
// density in the cell). Delta and ratio tracking sample against it cell by cell, so a sparse
// heterogeneous volume is not tracked with one global majorant.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "core/math.h"
#include "media/media.h"

namespace nimbus {

// The least majorant (per cell width) of a cell where a medium may emit: the tracking kernels then
// visit every emitting cell, however thin its extinction (emission is gathered at tentative collisions).
inline constexpr double kEmissionCollisionsPerCell = 2.0;

class MajorantGrid {
 public:
  // resolution: cells along the longest axis (0 = chosen from the media: ~4 voxels per cell for
  // grids, 32 for analytic shapes, at most 128). global = one cell over everything (for tests:
  // the naive tracker that judges the grid).
  // exact: the cells' density maxima from the voxels themselves rather than from the 8^3 bricks'
  // maxima (SceneMedia::max_density's `exact`): tighter, slower to build (the mfs photons' own grid).
  explicit MajorantGrid(const SceneMedia& media, int resolution = 0, bool global = false, bool exact = false);

  const Bounds& bounds() const { return bounds_; }
  std::array<int, 3> resolution() const { return res_; }
  double cell_majorant(int x, int y, int z) const { return maj_[(size_t(z) * res_[1] + y) * res_[0] + x]; }
  // The mean majorant of the non-empty cells (0 when every cell is empty): the media's typical extinction.
  double mean_majorant() const {
    double sum = 0.0;
    size_t cells = 0;
    for (const double m : maj_)
      if (m > 0.0) sum += m, ++cells;
    return cells > 0 ? sum / double(cells) : 0.0;
  }
  // Whether a medium may emit in the cell that holds p (clamped to the grid; SceneMedia::may_emit).
  bool may_emit_at(const Vec3& p) const;
  size_t memory_bytes() const { return maj_.size() * sizeof(float) + emits_.size(); }

  // Visits the cells a ray crosses within [tmin, tmax] in order, calling
  // segment(t0, t1, majorant) -> bool (false stops). d need not be normalised; t is in units of d.
  template <typename F>
  void traverse(const Vec3& o, const Vec3& d, double tmin, double tmax, F&& segment) const;

 private:
  Bounds bounds_;
  std::array<int, 3> res_{1, 1, 1};
  Vec3 cell_size_{1.0};
  std::vector<float> maj_;
  std::vector<uint8_t> emits_;  // per cell: a medium may emit there (empty when no medium emits)
};

template <typename F>
void MajorantGrid::traverse(const Vec3& o, const Vec3& d, double tmin, double tmax, F&& segment) const {
  double t0, t1;
  if (bounds_.empty() || !bounds_.intersect(o, d, tmin, tmax, &t0, &t1)) return;
  // Amanatides-Woo 3-D DDA from the entry point.
  const Vec3 p = o + d * t0;
  std::array<int, 3> cell, step, stop;
  std::array<double, 3> next_t, delta_t;
  for (int a = 0; a < 3; ++a) {
    cell[a] = std::clamp(int((p[a] - bounds_.lo[a]) / cell_size_[a]), 0, res_[a] - 1);
    if (d[a] > 0.0) {
      step[a] = 1;
      stop[a] = res_[a];
      next_t[a] = t0 + (bounds_.lo[a] + (cell[a] + 1) * cell_size_[a] - p[a]) / d[a];
      delta_t[a] = cell_size_[a] / d[a];
    } else if (d[a] < 0.0) {
      step[a] = -1;
      stop[a] = -1;
      next_t[a] = t0 + (bounds_.lo[a] + cell[a] * cell_size_[a] - p[a]) / d[a];
      delta_t[a] = -cell_size_[a] / d[a];
    } else {
      step[a] = 0;
      stop[a] = -2;
      next_t[a] = std::numeric_limits<double>::infinity();
      delta_t[a] = std::numeric_limits<double>::infinity();
    }
  }
  double t = t0;
  while (true) {
    const int a = (next_t[0] < next_t[1]) ? (next_t[0] < next_t[2] ? 0 : 2) : (next_t[1] < next_t[2] ? 1 : 2);
    const double t_exit = std::min(next_t[a], t1);
    if (t_exit > t && !segment(t, t_exit, cell_majorant(cell[0], cell[1], cell[2]))) return;
    if (next_t[a] >= t1) return;
    t = t_exit;
    cell[a] += step[a];
    if (cell[a] == stop[a]) return;
    next_t[a] += delta_t[a];
  }
}

}  // namespace nimbus
