// A regular grid of nodes (bounds, nodes per axis, spacing) and its trilinear lookup: the layout the
// scatter grid, the beam grid and the shadow maps (TransmittanceGrid) share. Values live beside it in
// the grids themselves, node by node, x fastest.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>

#include "core/math.h"
#include "core/rng.h"

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

// How a deposit sample is spread over the nodes around it (the scatter grid's tally; ScatterGridSettings):
//   trilinear:  its value times the 8 trilinear weights, to all 8 nodes;
//   stochastic: its whole value to one of the 8, drawn with probability equal to its trilinear weight
//               (per axis the upper node with probability f_a: independent uniforms per sample);
//   stratified: the same draw, the uniforms of a flight's k-th sample frac(s + k alpha) (the R3
//               sequence, alpha = (1/phi3, 1/phi3^2, 1/phi3^3), shifted by one uniform triple s per
//               flight), so the choices along a track are spread out rather than independent.
// The two stochastic splats' expected tally is the trilinear one (each sample's uniforms are uniform);
// they write one node per sample instead of 8 (docs/benchmarks.md, issue 12).
enum class Splat { trilinear, stochastic, stratified };

// The corner (bit a: upper node along axis a, the TrilinearStencil's numbering) of the cell of the
// point with fractional coordinates f (each in [0, 1]) that uniforms u (each in [0, 1)) draw: upper
// along axis a iff u_a < f_a, so corner k has probability equal to its trilinear weight.
inline int trilinear_corner(const double f[3], const double u[3]) {
  return (u[0] < f[0] ? 1 : 0) | (u[1] < f[1] ? 2 : 0) | (u[2] < f[2] ? 4 : 0);
}

// The uniforms of a flight's deposit samples for a stochastic or stratified splat, from a photon's own
// splat stream (so the tally does not depend on the thread count).
class CornerUniforms {
 public:
  CornerUniforms(Splat mode, Rng* rng) : mode_(mode), rng_(rng) {}
  // A new flight (stratified: a new shift).
  void start_flight() {
    if (mode_ == Splat::stratified)
      for (double& s : shift_) s = rng_->next_u32() * 0x1.0p-32;
  }
  // The uniforms of the flight's sample k.
  void next(int k, double u[3]) {
    if (mode_ == Splat::stratified) {
      constexpr double kAlpha[3] = {0.8191725133961645, 0.6710436067037893, 0.5497004779019703};
      for (int a = 0; a < 3; ++a) {
        const double v = shift_[a] + k * kAlpha[a];
        u[a] = v - std::floor(v);
      }
    } else {
      for (int a = 0; a < 3; ++a) u[a] = rng_->next_u32() * 0x1.0p-32;
    }
  }

 private:
  Splat mode_;
  Rng* rng_;
  double shift_[3] = {0.0, 0.0, 0.0};
};

// The node that uniforms u draw among the 8 around p (clamped into the grid) with probability equal to
// its trilinear weight (trilinear_corner).
inline size_t trilinear_random_node(const Vec3& p, const Vec3& lo, const Vec3& spacing,
                                    const std::array<int, 3>& nodes, const double u[3]) {
  int i[3];
  double f[3];
  for (int a = 0; a < 3; ++a) {
    const double t = std::clamp((p[a] - lo[a]) / spacing[a], 0.0, double(nodes[a] - 1));
    i[a] = std::min(int(t), nodes[a] - 2);
    f[a] = t - i[a];
  }
  const int k = trilinear_corner(f, u);
  return (size_t(i[2] + (k >> 2)) * nodes[1] + i[1] + (k >> 1 & 1)) * nodes[0] + i[0] + (k & 1);
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
  // One of them, drawn with probability equal to its weight by uniforms u (trilinear_random_node).
  size_t random_node(const Vec3& p, const double u[3]) const {
    return trilinear_random_node(p, bounds.lo, spacing, nodes, u);
  }
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
// media has a node's full support around it; `resolution` nodes along the longest axis and proportionally
// fewer along the others (a flat axis gets a spacing of 1e-6 of the longest). The scatter and beam grids'
// layout. With `sigma`, the media's typical extinction, an axis shorter than a quarter of the longest gets at
// least one node per kFlatAxisDepth optical depths of its extent (at most `resolution`): across a wide layer
// the light changes over a few transport lengths however wide the layer is, and the proportional count gave
// an 80 x 80 x 4 layer of 16 optical depths 4 nodes across it, 6 % dark (docs/benchmarks.md, "A flat
// layer"). Axes of a quarter of the longest or more keep the proportional count (the suite's spheres, box and
// clouds: their grids are unchanged).
inline constexpr double kFlatAxisDepth = 1.6;
inline NodeGrid node_grid_padded(const Bounds& media_bounds, int resolution, double sigma = 0.0) {
  NodeGrid g;
  const Vec3 extent = media_bounds.hi - media_bounds.lo;
  const double longest = std::max({extent.x, extent.y, extent.z});
  for (int a = 0; a < 3; ++a) {
    int inner = std::max(2, int(std::ceil(extent[a] / longest * (resolution - 1))) + 1);
    if (sigma > 0.0 && extent[a] < 0.25 * longest && std::isfinite(extent[a] * sigma))
      inner = std::max(inner,
                       int(std::min(double(resolution), std::ceil(extent[a] * sigma / kFlatAxisDepth))) + 1);
    g.spacing[a] = std::max(extent[a], 1e-6 * longest) / (inner - 1);
    g.nodes[a] = inner + 2;
    g.bounds.lo[a] = media_bounds.lo[a] - g.spacing[a];
    g.bounds.hi[a] = g.bounds.lo[a] + g.spacing[a] * (g.nodes[a] - 1);
  }
  return g;
}

}  // namespace nimbus
