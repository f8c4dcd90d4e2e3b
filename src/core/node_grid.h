// A regular grid of nodes (bounds, nodes per axis, spacing) and its trilinear lookup: the layout the
// scatter grid, the beam grid and the shadow maps (TransmittanceGrid) share. Values live beside it in
// the grids themselves, node by node, x fastest.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
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

struct NodeGrid {
  Bounds bounds{Vec3(0.0), Vec3(1.0)};  // lo: node (0, 0, 0); hi: the last node (see the layouts)
  std::array<int, 3> nodes{2, 2, 2};    // per axis, each >= 2
  Vec3 spacing{1.0};                    // between neighbouring nodes, per axis

  size_t size() const { return size_t(nodes[0]) * nodes[1] * nodes[2]; }
  size_t index(int x, int y, int z) const { return (size_t(z) * nodes[1] + y) * nodes[0] + x; }
  Vec3 position(int x, int y, int z) const { return bounds.lo + Vec3(x, y, z) * spacing; }
  double min_spacing() const { return std::min({spacing.x, spacing.y, spacing.z}); }
  double cell_volume() const { return spacing.x * spacing.y * spacing.z; }
  // The 8 nodes around p and their trilinear weights (p clamped into the grid).
  TrilinearStencil stencil(const Vec3& p) const { return trilinear_stencil(p, bounds.lo, spacing, nodes); }
};

// Nodes on the box `b` itself (first and last node on its faces), `resolution` nodes along its longest
// axis and proportionally fewer (at least 2) along the others. The shadow maps' layout.
inline NodeGrid node_grid_spanning(const Bounds& b, int resolution) {
  NodeGrid g;
  g.bounds = b;
  const Vec3 extent = b.hi - b.lo;
  const double longest = std::max({extent.x, extent.y, extent.z});
  for (int a = 0; a < 3; ++a) {
    g.nodes[a] = std::max(2, int(std::ceil(extent[a] / longest * (resolution - 1))) + 1);
    g.spacing[a] = extent[a] / (g.nodes[a] - 1);
  }
  return g;
}

// Nodes covering the media's bounds, plus one spacing of padding on each side so every point of the
// media has a node's full support around it; `resolution` nodes along the longest axis (a flat axis
// gets a spacing of 1e-6 of the longest). The scatter and beam grids' layout.
inline NodeGrid node_grid_padded(const Bounds& media_bounds, int resolution) {
  NodeGrid g;
  const Vec3 extent = media_bounds.hi - media_bounds.lo;
  const double longest = std::max({extent.x, extent.y, extent.z});
  for (int a = 0; a < 3; ++a) {
    const int inner = std::max(2, int(std::ceil(extent[a] / longest * (resolution - 1))) + 1);
    g.spacing[a] = std::max(extent[a], 1e-6 * longest) / (inner - 1);
    g.nodes[a] = inner + 2;
    g.bounds.lo[a] = media_bounds.lo[a] - g.spacing[a];
    g.bounds.hi[a] = g.bounds.lo[a] + g.spacing[a] * (g.nodes[a] - 1);
  }
  return g;
}

}  // namespace nimbus
