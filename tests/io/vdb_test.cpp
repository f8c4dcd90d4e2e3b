// DensityGrid on the shared test volumes: the numbers of SOURCES.md (an independent description of
// the files), trilinear sampling against an independent formula, the brick max bound against brute
// force, and the bad-input catalogue on real files (missing, empty, truncated, bit-flipped, text).
#include "io/vdb.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <optional>
#include <random>

#include "io/vdb_test_util.h"
#include "nimbus/error.h"

namespace nimbus {
namespace {

using test::kCloud;
using test::kSmoke;
using test::shared_volume;

// Loading is ~30 ms; share one load per file across the tests of this file.
const DensityGrid& cached(const char* name) {
  static std::map<std::string, DensityGrid> grids;
  auto it = grids.find(name);
  if (it == grids.end()) it = grids.emplace(name, load_density_grid(shared_volume(name))).first;
  return it->second;
}

TEST(VdbLoad, CloudMatchesSources) {
  NIMBUS_REQUIRE_FILE(shared_volume(kCloud));
  const DensityGrid& g = cached(kCloud);
  const auto& s = g.stats();
  EXPECT_EQ(s.name, "density");
  EXPECT_EQ(s.active_voxels, 415642u);
  EXPECT_EQ(s.tiles, 130u);
  EXPECT_EQ(s.index_min, (std::array<int, 3>{-66, -21, -90}));
  EXPECT_EQ(s.index_max, (std::array<int, 3>{59, 64, 63}));
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(s.voxel_size[a], 3.333, 1e-3);
  EXPECT_GE(s.min_value, 0.0);
  EXPECT_LE(s.max_value, 1.0);
  EXPECT_GT(s.max_value, 0.99);
  EXPECT_EQ(s.negative_count, 0u);
  EXPECT_EQ(g.index_lo(), Vec3(-67, -22, -91));
  EXPECT_EQ(g.index_hi(), Vec3(60, 65, 64));
  // SOURCES.md: the mean over non-zero voxels is 0.52 (active voxels, tiles counted voxel by voxel).
  const auto& grid = g.nano_grid();
  auto acc = grid.getAccessor();
  double sum = 0;
  uint64_t n = 0;
  for (int i = s.index_min[0]; i <= s.index_max[0]; ++i)
    for (int j = s.index_min[1]; j <= s.index_max[1]; ++j)
      for (int k = s.index_min[2]; k <= s.index_max[2]; ++k) {
        const nanovdb::Coord ijk(i, j, k);
        const float v = acc.getValue(ijk);
        if (acc.isActive(ijk) && v != 0.0f) sum += v, n++;
      }
  EXPECT_NEAR(sum / n, 0.52, 0.005);
}

TEST(VdbLoad, SmokeMatchesSources) {
  NIMBUS_REQUIRE_FILE(shared_volume(kSmoke));
  const DensityGrid& g = cached(kSmoke);
  const auto& s = g.stats();
  EXPECT_EQ(s.name, "");
  EXPECT_EQ(s.active_voxels, 1049275u);
  EXPECT_EQ(s.index_min, (std::array<int, 3>{1, 2, 1}));
  EXPECT_EQ(s.index_max, (std::array<int, 3>{111, 223, 112}));
  EXPECT_EQ(s.voxel_size, Vec3(1.0));
  EXPECT_GE(s.min_value, 0.0);
  EXPECT_NEAR(s.max_value, 5.71, 0.01);
  EXPECT_EQ(s.negative_count, 0u);
  EXPECT_GE(g.max_density(), s.max_value);
  EXPECT_LE(g.max_density(), s.max_value * 1.00001);
}

TEST(VdbLoad, WorldIndexMapsAndBounds) {
  NIMBUS_REQUIRE_FILE(shared_volume(kCloud));
  const DensityGrid& g = cached(kCloud);
  const double h = g.stats().voxel_size.x;
  const Vec3 p(1.25, -7.5, 30.0);
  EXPECT_LT((g.index_to_world(p) - p * h).length(), 1e-9 * h);  // the cloud's map is a pure scale
  EXPECT_LT((g.world_to_index(g.index_to_world(p)) - p).length(), 1e-9);
  const Bounds b = g.world_bounds();
  EXPECT_LT((b.lo - g.index_lo() * h).length(), 1e-9);
  EXPECT_LT((b.hi - g.index_hi() * h).length(), 1e-9);
}

TEST(VdbLoad, CopiesShareAndOutliveTheOriginal) {
  NIMBUS_REQUIRE_FILE(shared_volume(kSmoke));
  std::optional<DensityGrid> a = load_density_grid(shared_volume(kSmoke));
  const Vec3 p(50.3, 100.7, 40.2);
  const double d = a->density_index(p);
  DensityGrid b = *a;
  DensityGrid c = std::move(*a);
  a.reset();
  EXPECT_EQ(b.density_index(p), d);
  EXPECT_EQ(c.density_index(p), d);
  EXPECT_EQ(&b.nano_grid(), &c.nano_grid());
}

// density_index keeps one accessor per thread for the grid it read last: reads that alternate between
// grids, and a grid loaded after another was freed (which may reuse its memory), must give what a
// fresh accessor (DensityGrid::Sampler) gives.
TEST(VdbLoad, CachedAccessorFollowsTheGridRead) {
  NIMBUS_REQUIRE_FILE(shared_volume(kSmoke));
  NIMBUS_REQUIRE_FILE(shared_volume(kCloud));
  std::mt19937_64 gen(11);
  auto check = [&](const DensityGrid& a, const DensityGrid& b) {
    DensityGrid::Sampler sa(a), sb(b);
    int nonzero = 0;
    for (int i = 0; i < 2000; ++i) {
      const DensityGrid& g = i % 3 ? a : b;
      DensityGrid::Sampler& s = i % 3 ? sa : sb;
      Vec3 p;
      for (int k = 0; k < 3; ++k)
        p[k] = std::uniform_real_distribution<double>(g.index_lo()[k], g.index_hi()[k])(gen);
      const double expected = s.density_index(p);
      ASSERT_EQ(g.density_index(p), expected) << i;
      nonzero += expected > 0.0;
    }
    EXPECT_GT(nonzero, 100);
  };
  for (int round = 0; round < 3; ++round) {
    const DensityGrid smoke = load_density_grid(shared_volume(kSmoke));
    const DensityGrid cloud = load_density_grid(shared_volume(round == 1 ? kSmoke : kCloud));
    check(smoke, cloud);
  }
}

// ---- sampling -----------------------------------------------------------------------------------

class VdbSample : public ::testing::TestWithParam<const char*> {};

TEST_P(VdbSample, VoxelCentresGiveVoxelValues) {
  NIMBUS_REQUIRE_FILE(shared_volume(GetParam()));
  const DensityGrid& g = cached(GetParam());
  auto acc = g.nano_grid().getAccessor();
  DensityGrid::Sampler sampler(g);
  const auto& s = g.stats();
  std::mt19937_64 rng(1);
  int nonzero = 0;
  for (int n = 0; n < 20000; ++n) {
    nanovdb::Coord ijk;
    for (int a = 0; a < 3; ++a)
      ijk[a] = std::uniform_int_distribution<int>(s.index_min[a], s.index_max[a])(rng);
    const double expected = std::max(0.0f, acc.getValue(ijk));
    const Vec3 p(ijk[0], ijk[1], ijk[2]);
    ASSERT_EQ(g.density_index(p), expected) << ijk[0] << " " << ijk[1] << " " << ijk[2];
    ASSERT_EQ(sampler.density_index(p), expected);
    nonzero += expected > 0;
  }
  EXPECT_GT(nonzero, 1000);
}

TEST_P(VdbSample, BetweenVoxelsIsTrilinear) {
  NIMBUS_REQUIRE_FILE(shared_volume(GetParam()));
  const DensityGrid& g = cached(GetParam());
  auto acc = g.nano_grid().getAccessor();
  DensityGrid::Sampler sampler(g);
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Vec3 lo = g.index_lo(), hi = g.index_hi();
  for (int n = 0; n < 50000; ++n) {
    const Vec3 p(lo.x + u(rng) * (hi.x - lo.x), lo.y + u(rng) * (hi.y - lo.y), lo.z + u(rng) * (hi.z - lo.z));
    // Independent formula: sum over the 8 corners of product weights times corner value.
    const int i = int(std::floor(p.x)), j = int(std::floor(p.y)), k = int(std::floor(p.z));
    const double fx = p.x - i, fy = p.y - j, fz = p.z - k;
    double expected = 0;
    for (int c = 0; c < 8; ++c) {
      const int dx = c & 1, dy = (c >> 1) & 1, dz = (c >> 2) & 1;
      const double w = (dx ? fx : 1 - fx) * (dy ? fy : 1 - fy) * (dz ? fz : 1 - fz);
      expected += w * std::max(0.0f, acc.getValue(nanovdb::Coord(i + dx, j + dy, k + dz)));
    }
    ASSERT_NEAR(g.density_index(p), expected, 1e-6 * (1 + expected)) << p;
    ASSERT_EQ(sampler.density_index(p), g.density_index(p));
  }
}

TEST_P(VdbSample, ZeroOutsideTheDilatedBBox) {
  NIMBUS_REQUIRE_FILE(shared_volume(GetParam()));
  const DensityGrid& g = cached(GetParam());
  const Vec3 lo = g.index_lo(), hi = g.index_hi(), mid = (lo + hi) * 0.5;
  for (int a = 0; a < 3; ++a) {
    Vec3 p = mid, q = mid;
    p[a] = lo[a] - 1e-9;
    q[a] = hi[a] + 1e-9;
    EXPECT_EQ(g.density_index(p), 0.0);
    EXPECT_EQ(g.density_index(q), 0.0);
    EXPECT_EQ(g.max_density_index(p - Vec3(5), p), 0.0);
  }
  EXPECT_EQ(g.density_index(Vec3(std::nan(""), 0, 0)), 0.0);
}

// The brick max never falls below the density at any point of the box.
TEST_P(VdbSample, BrickMaxBoundsTheDensity) {
  NIMBUS_REQUIRE_FILE(shared_volume(GetParam()));
  const DensityGrid& g = cached(GetParam());
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Vec3 lo = g.index_lo() - Vec3(4), ext = g.index_hi() - g.index_lo() + Vec3(8);
  DensityGrid::Sampler sampler(g);
  // Single points (a box of zero size), many of them on brick borders.
  for (int n = 0; n < 200000; ++n) {
    Vec3 p(lo.x + u(rng) * ext.x, lo.y + u(rng) * ext.y, lo.z + u(rng) * ext.z);
    if (n % 4 == 0) p.x = g.index_lo().x + 8 * std::round((p.x - g.index_lo().x) / 8) - 1e-7 * (n % 8 == 0);
    ASSERT_LE(sampler.density_index(p), g.max_density_index(p, p)) << p;
  }
  // Boxes of many sizes: brute force over a dense lattice of points plus random points in the box.
  double tightness = 0;
  for (int n = 0; n < 300; ++n) {
    const double size = std::pow(2.0, u(rng) * 6.0 - 1.0);
    const Vec3 a(lo.x + u(rng) * ext.x, lo.y + u(rng) * ext.y, lo.z + u(rng) * ext.z);
    const Vec3 b = a + Vec3(size * (0.2 + u(rng)), size * (0.2 + u(rng)), size * (0.2 + u(rng)));
    const double bound = g.max_density_index(a, b);
    double brute = 0;
    const int m = 12;
    for (int i = 0; i <= m; ++i)
      for (int j = 0; j <= m; ++j)
        for (int k = 0; k <= m; ++k)
          brute = std::max(brute, sampler.density_index(a + Vec3((b.x - a.x) * i / m, (b.y - a.y) * j / m,
                                                                 (b.z - a.z) * k / m)));
    for (int r = 0; r < 500; ++r)
      brute =
          std::max(brute, sampler.density_index(Vec3(a.x + u(rng) * (b.x - a.x), a.y + u(rng) * (b.y - a.y),
                                                     a.z + u(rng) * (b.z - a.z))));
    ASSERT_LE(brute, bound) << a << " " << b;
    tightness = std::max(tightness, bound - brute);
  }
  // The whole grid: the bound is the largest value (plus the documented 1e-6 slack).
  EXPECT_NEAR(g.max_density_index(g.index_lo(), g.index_hi()), g.stats().max_value,
              2e-6 * g.stats().max_value);
}

INSTANTIATE_TEST_SUITE_P(SharedFiles, VdbSample, ::testing::Values(kCloud, kSmoke), [](const auto& info) {
  return std::string(info.param[0] == 'w' ? "Cloud" : "Smoke");
});

// ---- bad input on real files --------------------------------------------------------------------

TEST(VdbErrors, MissingEmptyDirectoryAndText) {
  test::ScratchDir dir("vdb_err");
  EXPECT_NE(test::load_error(dir / "nope.vdb").find("nope.vdb: no such file"), std::string::npos);
  test::write_bytes(dir / "empty.vdb", {});
  EXPECT_NE(test::load_error(dir / "empty.vdb").find("empty.vdb: empty file"), std::string::npos);
  std::filesystem::create_directories(dir / "dir.vdb");
  EXPECT_NE(test::load_error(dir / "dir.vdb").find("directory"), std::string::npos);
  const std::string text = "# not a volume\nhello world\n";
  test::write_bytes(dir / "text.vdb", std::vector<char>(text.begin(), text.end()));
  EXPECT_NE(test::load_error(dir / "text.vdb").find("text.vdb: not a VDB or NanoVDB file"),
            std::string::npos);
  test::write_bytes(dir / "text.nvdb", std::vector<char>(text.begin(), text.end()));
  EXPECT_NE(test::load_error(dir / "text.nvdb").find("not a VDB or NanoVDB file"), std::string::npos);
  EXPECT_THROW(inspect_volume_file(dir / "text.vdb"), Error);
}

class VdbCorrupt : public ::testing::TestWithParam<const char*> {};

TEST_P(VdbCorrupt, TruncatedFilesGiveErrors) {
  const auto src = shared_volume(GetParam());
  NIMBUS_REQUIRE_FILE(src);
  const std::vector<char> bytes = test::read_bytes(src);
  test::ScratchDir dir("vdb_trunc");
  const auto file = dir / (std::string("cut") + src.extension().string());
  for (size_t n : {size_t(1), size_t(3), size_t(4), size_t(7), size_t(8), size_t(15), size_t(16), size_t(100),
                   size_t(200), size_t(1000), size_t(5000), bytes.size() / 3, bytes.size() / 2,
                   bytes.size() - 100, bytes.size() - 1}) {
    test::write_bytes(file, bytes, n);
    const std::string msg = test::load_error(file);
    EXPECT_NE(msg.find(file.string() + ": "), std::string::npos) << n << ": " << msg;
    EXPECT_THROW(inspect_volume_file(file), Error) << n;
  }
}

// Random bit flips in the header and anywhere in the file: an error or a good load, never a crash.
TEST_P(VdbCorrupt, BitFlipsNeverCrash) {
  const auto src = shared_volume(GetParam());
  NIMBUS_REQUIRE_FILE(src);
  const std::vector<char> bytes = test::read_bytes(src);
  test::ScratchDir dir("vdb_flip");
  const auto file = dir / (std::string("flip") + src.extension().string());
  std::mt19937_64 rng(4);
  int errors = 0, loads = 0;
  for (int n = 0; n < 80; ++n) {
    std::vector<char> b = bytes;
    const int flips = 1 + n % 3;
    for (int f = 0; f < flips; ++f) {
      const size_t limit = n % 2 == 0 ? std::min<size_t>(b.size(), 1024) : b.size();
      const size_t at = std::uniform_int_distribution<size_t>(0, limit - 1)(rng);
      b[at] = static_cast<char>(b[at] ^ (1 << (rng() % 8)));
    }
    test::write_bytes(file, b);
    const auto t0 = std::chrono::steady_clock::now();
    try {
      const DensityGrid g = load_density_grid(file);
      // A grid that loads must be usable.
      (void)g.density_index((g.index_lo() + g.index_hi()) * 0.5);
      (void)g.max_density_index(g.index_lo(), g.index_hi());
      loads++;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
      errors++;
    }
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (secs > 0.3) std::printf("[          ] slow case %d: %.2f s\n", n, secs);
  }
  EXPECT_GT(errors, 0);
  std::printf("[          ] %d loads, %d errors\n", loads, errors);
}

INSTANTIATE_TEST_SUITE_P(SharedFiles, VdbCorrupt, ::testing::Values(kCloud, kSmoke), [](const auto& info) {
  return std::string(info.param[0] == 'w' ? "Cloud" : "Smoke");
});

}  // namespace
}  // namespace nimbus
