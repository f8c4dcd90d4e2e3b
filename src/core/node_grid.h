// Trilinear interpolation on a regular node grid: the 8 nodes around a point and their weights.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>

#include "core/math.h"

namespace nimbus {

struct TrilinearStencil {
  size_t node[8];    // linear node index, x fastest
  double weight[8];  // sum to 1
};

// Nodes at lo + (i, j, k) * spacing, `nodes` per axis (each >= 2); p is clamped into the grid.
inline TrilinearStencil trilinear_stencil(const Vec3& p, const Vec3& lo, const Vec3& spacing,
                                          const std::array<int, 3>& nodes) {
  int i[3];
  double f[3];
  for (int a = 0; a < 3; ++a) {
    const double u = std::clamp((p[a] - lo[a]) / spacing[a], 0.0, double(nodes[a] - 1));
    i[a] = std::min(int(u), nodes[a] - 2);
    f[a] = u - i[a];
  }
  TrilinearStencil s;
  for (int k = 0; k < 8; ++k) {
    const int dx = k & 1, dy = (k >> 1) & 1, dz = (k >> 2) & 1;
    s.weight[k] = (dx ? f[0] : 1 - f[0]) * (dy ? f[1] : 1 - f[1]) * (dz ? f[2] : 1 - f[2]);
    s.node[k] = (size_t(i[2] + dz) * nodes[1] + i[1] + dy) * nodes[0] + i[0] + dx;
  }
  return s;
}

}  // namespace nimbus
