// The dense copy of a small density grid (DensityGrid::kDenseMaxBytes): lookups through it give the same
// bits as lookups through the tree (DensityGrid::without_dense), at random points, at voxel corners, on
// and just inside and outside the faces of the data bbox, outside it and at NaN; on the shared volumes
// and on an in-memory grid with negative values, an inactive non-zero leaf value and an active tile.
// Grids over the cap keep reading the tree.
#include <gtest/gtest.h>
#include <nanovdb/util/OpenToNanoVDB.h>
#include <openvdb/openvdb.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include "io/vdb.h"
#include "io/vdb_test_util.h"

namespace nimbus {
namespace {

// Bit for bit (a plain == would take -0.0 for 0.0).
bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// Compares the dense path of g with its tree path at n random points of the data bbox widened by 3
// voxels, at voxel corners, at points on, just inside and just outside each face and corner of the bbox,
// and at NaN; returns how many of the points have a non-zero density (so the test is not vacuous).
int expect_dense_equals_tree(const DensityGrid& g, int n, uint64_t seed) {
  EXPECT_TRUE(g.has_dense());
  const DensityGrid tree = g.without_dense();
  EXPECT_FALSE(tree.has_dense());
  DensityGrid::Sampler dense_sampler(g), tree_sampler(tree);
  int nonzero = 0, failures = 0;
  auto check = [&](const Vec3& p) {
    const double expected = tree_sampler.density_index(p);
    const double a = g.density_index(p), b = dense_sampler.density_index(p), c = tree.density_index(p);
    if (!same_bits(a, expected) || !same_bits(b, expected) || !same_bits(c, expected)) {
      if (++failures <= 5)
        ADD_FAILURE() << "at " << p << ": tree " << expected << ", dense " << a << " (sampler " << b << ")";
    }
    nonzero += expected > 0.0;
  };
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Vec3 lo = g.index_lo() - Vec3(3.0), hi = g.index_hi() + Vec3(3.0);
  for (int i = 0; i < n; ++i) {
    const Vec3 p(lo.x + u(rng) * (hi.x - lo.x), lo.y + u(rng) * (hi.y - lo.y), lo.z + u(rng) * (hi.z - lo.z));
    check(p);
    check(Vec3(std::floor(p.x), std::floor(p.y), std::floor(p.z)));  // a voxel centre: u = v = w = 0
  }
  // The faces: one coordinate on, just inside or just outside lo or hi, the others random.
  const double inf = std::numeric_limits<double>::infinity();
  for (int i = 0; i < n / 4; ++i)
    for (int a = 0; a < 3; ++a) {
      Vec3 p(g.index_lo().x + u(rng) * (g.index_hi().x - g.index_lo().x),
             g.index_lo().y + u(rng) * (g.index_hi().y - g.index_lo().y),
             g.index_lo().z + u(rng) * (g.index_hi().z - g.index_lo().z));
      for (const double face : {g.index_lo()[a], g.index_hi()[a]})
        for (const double q :
             {face, std::nextafter(face, -inf), std::nextafter(face, inf), face - 0.5, face + 0.5}) {
          p[a] = q;
          check(p);
        }
    }
  // The 8 corners of the bbox, each exactly and nudged in and out on every axis.
  for (int c = 0; c < 8; ++c)
    for (const double nudge : {0.0, -inf, inf}) {
      Vec3 p;
      for (int a = 0; a < 3; ++a) {
        const double x = (c >> a) & 1 ? g.index_hi()[a] : g.index_lo()[a];
        p[a] = nudge == 0.0 ? x : std::nextafter(x, nudge);
      }
      check(p);
    }
  check(Vec3(std::nan(""), 0.5 * (g.index_lo().y + g.index_hi().y), 0.5 * (g.index_lo().z + g.index_hi().z)));
  EXPECT_EQ(failures, 0);
  return nonzero;
}

TEST(VdbDense, SharedVolumesReadTheSameValuesAsTheTree) {
  for (const char* name : {test::kCloud, test::kSmoke}) {
    NIMBUS_REQUIRE_FILE(test::shared_volume(name));
    const DensityGrid g = load_density_grid(test::shared_volume(name));
    SCOPED_TRACE(name);
    // The bytes: 4 per voxel of the bbox widened by one voxel below and two above (what trilinear reads).
    const auto& s = g.stats();
    uint64_t voxels = 1;
    for (int a = 0; a < 3; ++a) voxels *= uint64_t(s.index_max[a] - s.index_min[a] + 4);
    EXPECT_EQ(s.dense_bytes, 4 * voxels);
    EXPECT_GT(expect_dense_equals_tree(g, 200000, 31), 50000);
  }
}

// The inline world -> index map of an axis-aligned grid (DensityGrid::world_to_index) against NanoVDB's
// worldToIndex: the same numbers (== also takes -0.0 for 0.0, the one difference allowed), and the same
// density bits, at random world points of the shared volumes and at the map's own translation.
TEST(VdbDense, AxisAlignedWorldToIndexIsNanoVdbs) {
  for (const char* name : {test::kCloud, test::kSmoke}) {
    NIMBUS_REQUIRE_FILE(test::shared_volume(name));
    const DensityGrid g = load_density_grid(test::shared_volume(name));
    SCOPED_TRACE(name);
    const auto& map = g.nano_grid().map();
    const Bounds wb = g.world_bounds();
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> u(-0.2, 1.2);
    int failures = 0;
    for (int i = 0; i < 100000; ++i) {
      Vec3 w(wb.lo.x + u(rng) * (wb.hi.x - wb.lo.x), wb.lo.y + u(rng) * (wb.hi.y - wb.lo.y),
             wb.lo.z + u(rng) * (wb.hi.z - wb.lo.z));
      if (i == 0) w = Vec3(map.mVecD[0], map.mVecD[1], map.mVecD[2]);  // index (0, 0, 0): zeros
      const auto q = g.nano_grid().worldToIndex(nanovdb::Vec3d(w.x, w.y, w.z));
      const Vec3 expected(q[0], q[1], q[2]), p = g.world_to_index(w);
      const DensityGrid tree = g.without_dense();
      if (p != expected || !same_bits(g.density_index(p), g.density_index(expected)) ||
          !same_bits(tree.density_index(p), tree.density_index(expected)))
        if (++failures <= 5) ADD_FAILURE() << "at " << w << ": " << p << " against NanoVDB's " << expected;
    }
    EXPECT_EQ(failures, 0);
  }
}

// Random values (some negative: clamped to 0 in the copy as in the tree), an inactive non-zero leaf
// value (read by both), an active tile (no leaf: the copy fills its block) and a background of -0.25
// (negative, clamped) outside.
TEST(VdbDense, NegativeValuesTilesAndBackground) {
  static bool init = (openvdb::initialize(), true);
  (void)init;
  auto grid = openvdb::FloatGrid::create(-0.25f);
  auto acc = grid->getAccessor();
  std::mt19937_64 rng(32);
  std::uniform_real_distribution<float> value(-0.5f, 2.0f);
  for (int i = -13; i < 9; ++i)
    for (int j = 3; j < 17; ++j)
      for (int k = -6; k < 5; ++k)
        if (rng() % 4 != 0) acc.setValueOn(openvdb::Coord(i, j, k), value(rng));
  acc.setValueOff(openvdb::Coord(2, 5, 2), 0.75f);
  grid->tree().addTile(1, openvdb::Coord(16, 8, 0), 1.5f, /*active=*/true);
  const DensityGrid g = DensityGrid::from_nanovdb(nanovdb::openToNanoVDB(*grid), "test grid");
  EXPECT_GT(g.stats().negative_count, 0u);
  EXPECT_GT(expect_dense_equals_tree(g, 100000, 33), 20000);
  // A tile voxel and the clamped background read through the copy.
  EXPECT_EQ(g.density_index(Vec3(20.0, 12.0, 4.0)), 1.5);
  EXPECT_EQ(g.density_index(Vec3(2.0, 5.0, 2.0)), 0.75);
  EXPECT_EQ(g.density_index(Vec3(-13.0, 3.0, 6.0)), 0.0);

  // Over the cap: no copy, the tree is read, and the values are the same.
  const DensityGrid capped = DensityGrid::from_nanovdb(nanovdb::openToNanoVDB(*grid), "test grid", 0.0, 0.0,
                                                       g.stats().dense_bytes - 1);
  EXPECT_FALSE(capped.has_dense());
  EXPECT_EQ(capped.stats().dense_bytes, 0u);
  const DensityGrid fits =
      DensityGrid::from_nanovdb(nanovdb::openToNanoVDB(*grid), "test grid", 0.0, 0.0, g.stats().dense_bytes);
  EXPECT_TRUE(fits.has_dense());
  const Vec3 p(3.3, 7.7, -1.2);
  EXPECT_TRUE(same_bits(capped.density_index(p), g.density_index(p)));
}

}  // namespace
}  // namespace nimbus
