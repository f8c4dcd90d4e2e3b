// The node grid shared by the scatter grid, the beam grid and the shadow maps: its two layouts, its
// indexing and its trilinear lookup (exact for linear functions, weights summing to 1, clamping).
#include "core/node_grid.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "core/check.h"
#include "core/rng.h"

namespace nimbus {
namespace {

double linear(const Vec3& p) { return 0.7 - 1.3 * p.x + 2.1 * p.y + 0.4 * p.z; }

// Values of f at the nodes of g, interpolated at p by g's stencil.
double interpolate(const NodeGrid& g, const std::vector<double>& values, const Vec3& p) {
  const TrilinearStencil st = g.stencil(p);
  double v = 0.0;
  for (int k = 0; k < 8; ++k) v += st.weight[k] * values[st.node[k]];
  return v;
}

template <typename F>
std::vector<double> sample_nodes(const NodeGrid& g, F&& f) {
  std::vector<double> values(g.size());
  for (int z = 0; z < g.nodes[2]; ++z)
    for (int y = 0; y < g.nodes[1]; ++y)
      for (int x = 0; x < g.nodes[0]; ++x) values[g.index(x, y, z)] = f(g.position(x, y, z));
  return values;
}

TEST(NodeGrid, SpanningLayoutPutsNodesOnTheBoxFaces) {
  const Bounds b{Vec3(-1.0, 0.0, 2.0), Vec3(3.0, 1.0, 2.5)};
  const NodeGrid g = node_grid_spanning(b, 9);
  EXPECT_EQ(g.nodes[0], 9);  // the longest axis
  EXPECT_EQ(g.nodes[1], 3);  // ceil(1/4 * 8) + 1
  EXPECT_EQ(g.nodes[2], 2);  // ceil(0.5/4 * 8) + 1
  for (int a = 0; a < 3; ++a) {
    EXPECT_DOUBLE_EQ(g.position(0, 0, 0)[a], b.lo[a]);
    EXPECT_NEAR(g.position(g.nodes[0] - 1, g.nodes[1] - 1, g.nodes[2] - 1)[a], b.hi[a], 1e-12);
  }
  EXPECT_EQ(g.size(), size_t(9 * 3 * 2));
  EXPECT_EQ(g.index(g.nodes[0] - 1, g.nodes[1] - 1, g.nodes[2] - 1), g.size() - 1);
}

TEST(NodeGrid, PaddedLayoutCoversTheMediaWithOneSpacingToSpare) {
  const Bounds media{Vec3(0.0, 0.0, 0.0), Vec3(2.0, 1.0, 0.0)};  // flat in z
  const NodeGrid g = node_grid_padded(media, 5);
  EXPECT_EQ(g.nodes[0], 5 + 2);
  for (int a = 0; a < 3; ++a) {
    EXPECT_GT(g.spacing[a], 0.0);
    EXPECT_NEAR(g.bounds.lo[a], media.lo[a] - g.spacing[a], 1e-15);
    EXPECT_NEAR(g.bounds.hi[a], g.bounds.lo[a] + g.spacing[a] * (g.nodes[a] - 1), 1e-15);
    EXPECT_GE(g.bounds.hi[a], media.hi[a] + g.spacing[a] * (1.0 - 1e-9));
  }
  EXPECT_DOUBLE_EQ(g.min_spacing(), g.spacing.z);
  EXPECT_DOUBLE_EQ(g.cell_volume(), g.spacing.x * g.spacing.y * g.spacing.z);
}

// An axis under a quarter of the longest gets at least a node per kFlatAxisDepth optical depths of its extent
// (at most `resolution`): an 80 x 80 x 4 layer of extinction 4 (16 optical depths across) 11 nodes across its
// thickness instead of 4; its long axes, a cube's axes and an axis of 0.3 of the longest keep their
// proportional counts; a flat axis of no extent stays at 2; the padding is one spacing as ever.
TEST(NodeGrid, AFlatAxisGetsANodePerFewOpticalDepths) {
  const Bounds layer{Vec3(-40.0, -40.0, -2.0), Vec3(40.0, 40.0, 2.0)};
  const NodeGrid plain = node_grid_padded(layer, 48), floored = node_grid_padded(layer, 48, 4.0);
  EXPECT_EQ(plain.nodes[2], 4 + 2);
  EXPECT_EQ(floored.nodes[2], 11 + 2);
  EXPECT_NEAR(floored.spacing.z * 10.0, 4.0, 1e-12);
  EXPECT_NEAR(floored.bounds.lo.z, -2.0 - floored.spacing.z, 1e-12);
  for (int a = 0; a < 2; ++a) EXPECT_EQ(floored.nodes[a], plain.nodes[a]);
  EXPECT_EQ(node_grid_padded(layer, 48, 1000.0).nodes[2], 49 + 2);  // at most `resolution` + 1 inner nodes
  const Bounds cube{Vec3(0.0), Vec3(10.0)}, slab3{Vec3(0.0), Vec3(10.0, 10.0, 3.0)};
  for (int a = 0; a < 3; ++a) {
    EXPECT_EQ(node_grid_padded(cube, 24, 100.0).nodes[a], node_grid_padded(cube, 24).nodes[a]);
    EXPECT_EQ(node_grid_padded(slab3, 24, 100.0).nodes[a], node_grid_padded(slab3, 24).nodes[a]);
  }
  const Bounds sheet{Vec3(0.0), Vec3(10.0, 10.0, 0.0)};
  EXPECT_EQ(node_grid_padded(sheet, 24, 100.0).nodes[2], 2 + 2);
}

TEST(NodeGrid, TrilinearWeightsSumToOneAndReproduceLinearFunctions) {
  const NodeGrid g = node_grid_padded(Bounds{Vec3(-1.0, 0.5, 2.0), Vec3(2.0, 1.5, 4.0)}, 7);
  const std::vector<double> values = sample_nodes(g, linear);
  Rng rng(3, 4);
  for (int i = 0; i < 1000; ++i) {
    Vec3 p;
    for (int a = 0; a < 3; ++a) p[a] = g.bounds.lo[a] + rng.uniform() * (g.bounds.hi[a] - g.bounds.lo[a]);
    const TrilinearStencil st = g.stencil(p);
    double sum = 0.0;
    for (int k = 0; k < 8; ++k) {
      EXPECT_GE(st.weight[k], 0.0);
      EXPECT_LT(st.node[k], g.size());
      sum += st.weight[k];
    }
    EXPECT_NEAR(sum, 1.0, 1e-12);
    EXPECT_NEAR(interpolate(g, values, p), linear(p), 1e-12) << p;
  }
  // At a node the lookup returns that node's value.
  EXPECT_NEAR(interpolate(g, values, g.position(3, 2, 1)), values[g.index(3, 2, 1)], 1e-12);
}

TEST(NodeGrid, PointsOutsideAreClampedToTheNearestBoundary) {
  const NodeGrid g = node_grid_spanning(Bounds{Vec3(0.0), Vec3(1.0)}, 4);
  const std::vector<double> values = sample_nodes(g, linear);
  const Vec3 outside(-5.0, 0.5, 7.0), clamped(0.0, 0.5, 1.0);
  EXPECT_NEAR(interpolate(g, values, outside), linear(clamped), 1e-12);
}

TEST(Check, DcheckIsCompiledAwayInReleaseBuilds) {
  int evaluated = 0;
  NIMBUS_DCHECK(++evaluated > 0);
  EXPECT_EQ(evaluated, NIMBUS_DEBUG_CHECKS ? 1 : 0);
}

#if NIMBUS_DEBUG_CHECKS
TEST(CheckDeathTest, FailedDcheckNamesTheConditionAndAborts) {
  EXPECT_DEATH(NIMBUS_DCHECK(1 + 1 == 3), "NIMBUS_DCHECK\\(1 \\+ 1 == 3\\) failed");
}
#endif

// Pearson's chi-square of corner counts (n draws) against the trilinear weights of fractions f
// (infinite if a corner of weight 0 was drawn).
double corner_chi2(const double f[3], const std::array<int, 8>& counts, int n) {
  double chi2 = 0.0;
  for (int k = 0; k < 8; ++k) {
    const double p = (k & 1 ? f[0] : 1 - f[0]) * (k & 2 ? f[1] : 1 - f[1]) * (k & 4 ? f[2] : 1 - f[2]);
    const double expected = p * n;
    if (expected > 0.0)
      chi2 += (counts[k] - expected) * (counts[k] - expected) / expected;
    else if (counts[k] > 0)
      return std::numeric_limits<double>::infinity();  // a corner of weight 0 drawn
  }
  return chi2;
}

// The stochastic splat's corner (trilinear_corner from CornerUniforms, independent or stratified along
// a flight) has probability equal to its trilinear weight: a chi-square test (7 degrees of freedom,
// 99.99 % point 29.9) at random fractions. The same test rejects the nearest corner, and a draw that
// picks each axis's upper node with probability 1 - f (the weights mirrored).
TEST(NodeGrid, StochasticCornerHasTheTrilinearProbabilities) {
  constexpr int kDraws = 20000;
  constexpr double kChi2Limit = 29.9;
  Rng pick(5, 0);
  for (Splat mode : {Splat::stochastic, Splat::stratified}) {
    for (int t = 0; t < 10; ++t) {
      const double f[3] = {pick.uniform(), pick.uniform(), t == 0 ? 0.0 : pick.uniform()};
      Rng rng(17, uint64_t(t));
      CornerUniforms corners(mode, &rng);
      corners.start_flight();
      std::array<int, 8> counts{}, nearest{}, mirrored{};
      for (int k = 0; k < kDraws; ++k) {
        double u[3];
        corners.next(k, u);
        ++counts[trilinear_corner(f, u)];
        const double g[3] = {1 - f[0], 1 - f[1], 1 - f[2]};
        ++mirrored[trilinear_corner(g, u)];
        ++nearest[(f[0] >= 0.5 ? 1 : 0) | (f[1] >= 0.5 ? 2 : 0) | (f[2] >= 0.5 ? 4 : 0)];
      }
      EXPECT_LT(corner_chi2(f, counts, kDraws), kChi2Limit) << int(mode) << " " << t;
      EXPECT_GT(corner_chi2(f, nearest, kDraws), kChi2Limit) << int(mode) << " " << t;
      if (std::abs(f[0] - 0.5) + std::abs(f[1] - 0.5) > 0.1)
        EXPECT_GT(corner_chi2(f, mirrored, kDraws), kChi2Limit) << int(mode) << " " << t;
    }
  }
}

// NodeGrid::random_node draws one of the stencil's nodes with its weight: the mean of a tally of many
// unit samples at random points, one node each, equals the trilinear tally within its noise (per node,
// 5 binomial standard errors), and no node outside the stencils is written.
TEST(NodeGrid, RandomNodeTallyMatchesTrilinear) {
  const NodeGrid g = node_grid_padded(Bounds{Vec3(0.0), Vec3(2.0, 1.0, 1.0)}, 5);
  std::vector<double> tri(g.size(), 0.0), one(g.size(), 0.0);
  Rng rng(23, 0), splat(29, 0);
  CornerUniforms corners(Splat::stochastic, &splat);
  constexpr int kSamples = 200000;
  for (int i = 0; i < kSamples; ++i) {
    // Points in a small box so that each node gets many samples.
    const Vec3 p(0.4 + 0.3 * rng.uniform(), 0.3 + 0.3 * rng.uniform(), 0.5 + 0.2 * rng.uniform());
    const TrilinearStencil st = g.stencil(p);
    for (int k = 0; k < 8; ++k) tri[st.node[k]] += st.weight[k];
    double u[3];
    corners.next(i, u);
    one[g.random_node(p, u)] += 1.0;
  }
  int written = 0;
  for (size_t n = 0; n < g.size(); ++n) {
    if (tri[n] == 0.0) {
      EXPECT_EQ(one[n], 0.0);
      continue;
    }
    ++written;
    // Each sample lands on n with probability w_n(p): variance sum w (1 - w) <= tri[n].
    EXPECT_NEAR(one[n], tri[n], 5.0 * std::sqrt(tri[n]) + 1e-9) << n;
  }
  EXPECT_GE(written, 8);
}

}  // namespace
}  // namespace nimbus
