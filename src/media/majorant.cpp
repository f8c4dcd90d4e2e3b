#include "media/majorant.h"

#include <tbb/parallel_for.h>

#include "media/density_grid.h"

namespace nimbus {

namespace {

// Smallest voxel edge (world units) of the grid media, 0 when there are none. (Without a transform the
// x edge stands for all three, as it always has; with one, the shortest of the three transformed edges.)
double finest_voxel(const SceneMedia& media) {
  double best = 0.0;
  for (int i = 0; i < media.count(); ++i) {
    const Shape& s = media.medium(i).shape;
    const DensityGrid* g = nullptr;
    double scale = 1.0;
    if (const auto* v = std::get_if<VdbShape>(&s)) {
      g = v->data.get();
      scale = v->scale;
    } else if (const auto* c = std::get_if<CloudShape>(&s)) {
      g = c->data.get();
    }
    if (!g) continue;
    const Transform& t = media.medium(i).transform;
    double voxel = length(g->index_to_world(Vec3(1, 0, 0)) - g->index_to_world(Vec3(0, 0, 0))) * scale;
    if (!t.is_identity()) {  // the shortest voxel edge once transformed (a non-uniform scale differs per axis)
      voxel = std::numeric_limits<double>::infinity();
      for (int a = 0; a < 3; ++a) {
        Vec3 e(0.0);
        e[a] = 1.0;
        voxel =
            std::min(voxel, length(t.vector((g->index_to_world(e) - g->index_to_world(Vec3(0.0))) * scale)));
      }
    }
    if (voxel > 0.0 && (best == 0.0 || voxel < best)) best = voxel;
  }
  return best;
}

}  // namespace

MajorantGrid::MajorantGrid(const SceneMedia& media, int resolution, bool global, bool exact) {
  bounds_ = media.bounds();
  if (bounds_.empty()) {
    maj_.assign(1, 0.0f);
    return;
  }
  // Pad so that points on the boundary fall inside.
  const Vec3 pad = (bounds_.hi - bounds_.lo) * 1e-6 + Vec3(1e-9);
  bounds_.lo -= pad;
  bounds_.hi += pad;
  const Vec3 extent = bounds_.hi - bounds_.lo;
  const double longest = std::max({extent.x, extent.y, extent.z});
  if (global) {
    res_ = {1, 1, 1};
  } else {
    double cell = longest / 32.0;
    if (resolution > 0) {
      cell = longest / resolution;
    } else if (const double voxel = finest_voxel(media); voxel > 0.0) {
      cell = std::max(4.0 * voxel, longest / 128.0);
    }
    for (int a = 0; a < 3; ++a) res_[a] = std::clamp(int(std::ceil(extent[a] / cell)), 1, 256);
  }
  for (int a = 0; a < 3; ++a) cell_size_[a] = extent[a] / res_[a];
  maj_.assign(size_t(res_[0]) * res_[1] * res_[2], 0.0f);
  if (media.emits()) emits_.assign(maj_.size(), 0);
  const double min_cell = std::min({cell_size_.x, cell_size_.y, cell_size_.z});
  tbb::parallel_for(0, res_[2], [&](int z) {
    for (int y = 0; y < res_[1]; ++y) {
      for (int x = 0; x < res_[0]; ++x) {
        Bounds cell;
        cell.lo = bounds_.lo + Vec3(x, y, z) * cell_size_;
        cell.hi = cell.lo + cell_size_;
        double m = 0.0;
        for (int i = 0; i < media.count(); ++i) {
          const Medium& med = media.medium(i);
          const double d = media.max_density(i, cell, exact);
          if (d > 0.0) m += d * max_component(med.sigma_s + med.sigma_a);
        }
        // Emitting cells get at least kEmissionCollisionsPerCell tentative collisions per cell width, so
        // that thin or transparent emitters are sampled (media/emission.h).
        const size_t index = (size_t(z) * res_[1] + y) * res_[0] + x;
        for (int i = 0; i < media.count() && media.emits(); ++i)
          if (media.may_emit(i, cell)) {
            m = std::max(m, kEmissionCollisionsPerCell / min_cell);
            emits_[index] = 1;
          }
        // Round up so the float never falls below the double bound.
        maj_[index] = m > 0.0 ? std::nextafter(float(m), INFINITY) : 0.0f;
      }
    }
  });
}

bool MajorantGrid::may_emit_at(const Vec3& p) const {
  if (emits_.empty()) return false;
  size_t index = 0;
  for (int a = 2; a >= 0; --a)  // the cell as traverse finds it
    index = index * size_t(res_[a]) +
            size_t(std::clamp(int((p[a] - bounds_.lo[a]) / cell_size_[a]), 0, res_[a] - 1));
  return emits_[index] != 0;
}

}  // namespace nimbus
