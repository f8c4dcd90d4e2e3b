// The procedural cloud: deterministic, bounded, and a real cloud (a substantial, connected body).
#include "media/cloud.h"

#include <gtest/gtest.h>

#include "io/scene_volumes.h"
#include "media/density_grid.h"

namespace nimbus {
namespace {

TEST(Cloud, DensityIsDeterministicAndBounded) {
  double inside = 0.0, total = 0.0;
  const int n = 40;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        const Vec3 p((i + 0.5) / n * 2 - 1, (j + 0.5) / n * 2 - 1, (k + 0.5) / n * 2 - 1);
        const double d = procedural_cloud_density(p, 7);
        ASSERT_GE(d, 0.0);
        ASSERT_LE(d, 1.0);
        ASSERT_EQ(d, procedural_cloud_density(p, 7));
        if (p.length() > 0.98) ASSERT_EQ(d, 0.0);
        inside += d > 0.0;
        total += 1;
      }
  // A cumulus fills a good part of its bounding ball but not all of it.
  EXPECT_GT(inside / total, 0.05);
  EXPECT_LT(inside / total, 0.45);
  EXPECT_GT(procedural_cloud_density(Vec3(0, 0, 0), 7), 0.5);
  // Another seed gives another cloud.
  int differ = 0, occupied = 0;
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 20; ++j)
      for (int k = 0; k < 20; ++k) {
        const Vec3 p = Vec3(i, j, k) * (1.8 / 19) - Vec3(0.9);
        const double a = procedural_cloud_density(p, 7), b = procedural_cloud_density(p, 8);
        occupied += a > 0 || b > 0;
        differ += a != b;
      }
  EXPECT_GT(differ, occupied / 5);
}

TEST(Cloud, VoxelisedGridMatchesTheDensity) {
  CloudShape c;
  c.center = Vec3(1, 2, 3);
  c.radius = 2.0;
  c.seed = 7;
  c.resolution = 48;
  build_cloud_shape(c);
  const DensityGrid& g = *c.data;
  // At voxel centres the grid holds the density.
  for (int i = 3; i < 45; i += 7)
    for (int j = 3; j < 45; j += 5)
      for (int k = 3; k < 45; k += 6) {
        const Vec3 world = g.index_to_world(Vec3(i, j, k));
        const Vec3 unit = (world - c.center) / c.radius;
        EXPECT_NEAR(g.density_index(Vec3(i, j, k)), procedural_cloud_density(unit, 7), 1e-6);
      }
}

}  // namespace
}  // namespace nimbus
