// DensityGrid against OpenVDB itself: the .vdb -> NanoVDB conversion keeps the values (OpenVDB's own
// BoxSampler as the reference), small synthetic grids written here round-trip through .vdb and .nvdb
// (uncompressed, ZIP, BLOSC), and the error catalogue for grids OpenVDB can write but we must refuse.
#include "io/vdb.h"

#include <gtest/gtest.h>
#include <nanovdb/util/IO.h>
#include <nanovdb/util/OpenToNanoVDB.h>
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>

#include <cmath>
#include <random>

#include "io/vdb_test_util.h"
#include "nimbus/error.h"

namespace nimbus {
namespace {

void init() {
  static bool done = (openvdb::initialize(), true);
  (void)done;
}

void write_vdb(const std::filesystem::path& file, const openvdb::GridPtrVec& grids) {
  openvdb::io::File f(file.string());
  f.write(grids);
  f.close();
}

// A small fog volume with voxels, an active tile, inactive non-zero leaf values and a non-trivial map.
openvdb::FloatGrid::Ptr synthetic_grid() {
  auto grid = openvdb::FloatGrid::create(0.0f);
  grid->setName("density");
  grid->setGridClass(openvdb::GRID_FOG_VOLUME);
  auto xform = openvdb::math::Transform::createLinearTransform(0.5);
  xform->postTranslate(openvdb::Vec3d(1.0, -2.0, 3.0));
  grid->setTransform(xform);
  auto acc = grid->getAccessor();
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<float> u(0.0f, 2.0f);
  for (int i = -5; i < 13; ++i)
    for (int j = 0; j < 9; ++j)
      for (int k = -3; k < 4; ++k) acc.setValueOn(openvdb::Coord(i, j, k), u(rng));
  acc.setValueOff(openvdb::Coord(2, 2, 2), 0.75f);                           // inactive, still sampled
  grid->tree().addTile(1, openvdb::Coord(16, 0, 0), 1.5f, /*active=*/true);  // one 8^3 active tile
  return grid;
}

TEST(VdbOpenVdb, ConversionKeepsTheCloudValues) {
  const auto file = test::shared_volume(test::kCloud);
  NIMBUS_REQUIRE_FILE(file);
  init();
  openvdb::io::File f(file.string());
  f.open();
  auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(f.readGrid("density"));
  ASSERT_TRUE(grid);
  EXPECT_EQ(grid->activeVoxelCount(), 415642u);
  EXPECT_EQ(grid->tree().activeTileCount(), 130u);
  const DensityGrid g = load_density_grid(file);
  openvdb::tools::GridSampler<openvdb::FloatGrid, openvdb::tools::BoxSampler> ref(*grid);
  std::mt19937_64 rng(12);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Bounds wb = g.world_bounds();
  for (int n = 0; n < 50000; ++n) {
    const Vec3 w(wb.lo.x + u(rng) * (wb.hi.x - wb.lo.x), wb.lo.y + u(rng) * (wb.hi.y - wb.lo.y),
                 wb.lo.z + u(rng) * (wb.hi.z - wb.lo.z));
    const double expected = ref.wsSample(openvdb::Vec3d(w.x, w.y, w.z));
    ASSERT_NEAR(g.density_index(g.world_to_index(w)), expected, 1e-5) << w;
  }
}

class VdbSynthetic : public ::testing::TestWithParam<std::string> {};

TEST_P(VdbSynthetic, RoundTripsThroughEveryFormat) {
  init();
  test::ScratchDir dir("vdb_synth");
  const auto grid = synthetic_grid();
  std::filesystem::path file;
  if (GetParam() == "vdb") {
    file = dir / "synth.vdb";
    write_vdb(file, {grid});
  } else {
    file = dir / ("synth_" + GetParam() + ".nvdb");
    const auto codec = GetParam() == "zip"     ? nanovdb::io::Codec::ZIP
                       : GetParam() == "blosc" ? nanovdb::io::Codec::BLOSC
                                               : nanovdb::io::Codec::NONE;
    nanovdb::io::writeGrid(file.string(), nanovdb::openToNanoVDB(*grid), codec);
  }
  const DensityGrid g = load_density_grid(file);
  EXPECT_EQ(g.stats().name, "density");
  EXPECT_EQ(g.stats().active_voxels, grid->activeVoxelCount());
  EXPECT_EQ(g.stats().tiles, 1u);
  EXPECT_EQ(g.stats().index_min, (std::array<int, 3>{-5, 0, -3}));
  EXPECT_EQ(g.stats().index_max, (std::array<int, 3>{23, 8, 7}));
  EXPECT_EQ(g.stats().voxel_size, Vec3(0.5));
  EXPECT_EQ(g.density_index(Vec3(2, 2, 2)), 0.75);  // the inactive leaf value
  EXPECT_EQ(g.density_index(Vec3(20, 3, 4)), 1.5);  // inside the tile
  openvdb::tools::GridSampler<openvdb::FloatGrid, openvdb::tools::BoxSampler> ref(*grid);
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> u(-0.2, 1.2);
  const Vec3 lo = g.index_lo(), hi = g.index_hi();
  for (int n = 0; n < 20000; ++n) {
    const Vec3 p(lo.x + u(rng) * (hi.x - lo.x), lo.y + u(rng) * (hi.y - lo.y), lo.z + u(rng) * (hi.z - lo.z));
    const bool inside =
        p.x >= lo.x && p.y >= lo.y && p.z >= lo.z && p.x <= hi.x && p.y <= hi.y && p.z <= hi.z;
    const double expected = inside ? ref.isSample(openvdb::Vec3d(p.x, p.y, p.z)) : 0.0;
    ASSERT_NEAR(g.density_index(p), expected, 1e-6) << p;
    ASSERT_LE(g.density_index(p), g.max_density_index(p, p));
    const Vec3 w = g.index_to_world(p);
    const auto wr = grid->transform().indexToWorld(openvdb::Vec3d(p.x, p.y, p.z));
    ASSERT_NEAR((w - Vec3(wr[0], wr[1], wr[2])).length(), 0.0, 1e-9);
  }
  const auto infos = inspect_volume_file(file);
  ASSERT_EQ(infos.size(), 1u);
  EXPECT_EQ(infos[0].name, "density");
  EXPECT_EQ(infos[0].type, "float");
  EXPECT_EQ(infos[0].active_voxels, grid->activeVoxelCount());
  EXPECT_EQ(infos[0].tiles, 1u);
  EXPECT_TRUE(infos[0].has_value_range);
}

INSTANTIATE_TEST_SUITE_P(Formats, VdbSynthetic, ::testing::Values("vdb", "none", "zip", "blosc"));

TEST(VdbOpenVdb, GridSelectionAndTypeErrors) {
  init();
  test::ScratchDir dir("vdb_names");
  auto density = synthetic_grid();
  auto vel = openvdb::Vec3SGrid::create();
  vel->setName("vel");
  vel->tree().setValueOn(openvdb::Coord(1, 2, 3), openvdb::Vec3s(1, 0, 0));
  auto temp = openvdb::FloatGrid::create();
  temp->setName("temperature");
  temp->tree().setValueOn(openvdb::Coord(0, 0, 0), 300.0f);
  write_vdb(dir / "multi.vdb", {vel, density, temp});
  EXPECT_EQ(load_density_grid(dir / "multi.vdb").stats().name, "density");  // first float grid
  EXPECT_EQ(load_density_grid(dir / "multi.vdb", "temperature").stats().max_value, 300.0);
  std::string msg = test::load_error(dir / "multi.vdb", "smoke");
  EXPECT_NE(msg.find("multi.vdb: no grid named \"smoke\""), std::string::npos) << msg;
  EXPECT_NE(msg.find("\"vel\" (vec3s)"), std::string::npos) << msg;
  EXPECT_NE(msg.find("\"density\" (float)"), std::string::npos) << msg;
  msg = test::load_error(dir / "multi.vdb", "vel");
  EXPECT_NE(msg.find("vec3s, not float"), std::string::npos) << msg;
  write_vdb(dir / "vec.vdb", {vel});
  msg = test::load_error(dir / "vec.vdb");
  EXPECT_NE(msg.find("vec.vdb: no float grid"), std::string::npos) << msg;
  EXPECT_EQ(inspect_volume_file(dir / "multi.vdb").size(), 3u);
  // The same through NanoVDB files.
  std::vector<nanovdb::GridHandle<nanovdb::HostBuffer>> handles;
  handles.push_back(nanovdb::openToNanoVDB(*vel));
  handles.push_back(nanovdb::openToNanoVDB(*temp));
  nanovdb::io::writeGrids(dir / "multi.nvdb", handles, nanovdb::io::Codec::BLOSC);
  EXPECT_EQ(load_density_grid(dir / "multi.nvdb").stats().name, "temperature");
  msg = test::load_error(dir / "multi.nvdb", "smoke");
  EXPECT_NE(msg.find("\"vel\" (Vec3f)"), std::string::npos) << msg;
  msg = test::load_error(dir / "multi.nvdb", "vel");
  EXPECT_NE(msg.find("not float"), std::string::npos) << msg;
  const auto infos = inspect_volume_file(dir / "multi.nvdb");
  ASSERT_EQ(infos.size(), 2u);
  EXPECT_EQ(infos[0].type, "Vec3f");
  EXPECT_FALSE(infos[0].has_value_range);
}

TEST(VdbOpenVdb, NaNIsAnErrorNegativeIsClampedAndCounted) {
  init();
  test::ScratchDir dir("vdb_values");
  auto nan_grid = synthetic_grid();
  for (int i = 0; i < 3; ++i) nan_grid->tree().setValueOn(openvdb::Coord(i, 1, 1), std::nanf(""));
  write_vdb(dir / "nan.vdb", {nan_grid});
  std::string msg = test::load_error(dir / "nan.vdb");
  EXPECT_NE(msg.find("nan.vdb: 3 NaN/inf density values (first at index [0, 1, 1]"), std::string::npos)
      << msg;
  nanovdb::io::writeGrid((dir / "inf.nvdb").string(), nanovdb::openToNanoVDB(*nan_grid));
  EXPECT_NE(test::load_error(dir / "inf.nvdb").find("3 NaN/inf"), std::string::npos);

  auto neg = synthetic_grid();
  for (int i = 0; i < 5; ++i) neg->tree().setValueOn(openvdb::Coord(i, 4, 0), -1.0f);
  write_vdb(dir / "neg.vdb", {neg});
  const DensityGrid g = load_density_grid(dir / "neg.vdb");
  EXPECT_EQ(g.stats().negative_count, 5u);
  EXPECT_EQ(g.stats().min_value, -1.0);
  EXPECT_EQ(g.density_index(Vec3(2, 4, 0)), 0.0);
  EXPECT_GE(g.density_index(Vec3(2.5, 4.5, 0.5)), 0.0);
}

TEST(VdbOpenVdb, EmptyAndEnormousGridsAreRefused) {
  init();
  test::ScratchDir dir("vdb_size");
  auto empty = openvdb::FloatGrid::create();
  empty->setName("density");
  write_vdb(dir / "empty.vdb", {empty});
  EXPECT_NE(test::load_error(dir / "empty.vdb").find("empty"), std::string::npos);
  auto huge = openvdb::FloatGrid::create();
  huge->setName("density");
  huge->tree().setValueOn(openvdb::Coord(-2000, -2000, -2000), 1.0f);
  huge->tree().setValueOn(openvdb::Coord(2000, 2000, 2000), 1.0f);
  write_vdb(dir / "huge.vdb", {huge});
  EXPECT_NE(test::load_error(dir / "huge.vdb").find("too large"), std::string::npos);
  nanovdb::io::writeGrid((dir / "huge.nvdb").string(), nanovdb::openToNanoVDB(*huge),
                         nanovdb::io::Codec::ZIP);
  EXPECT_NE(test::load_error(dir / "huge.nvdb").find("too large"), std::string::npos);
}

// Headers that lie about sizes: errors before any allocation, for every codec.
TEST(VdbOpenVdb, NanoVdbHeadersClaimingATerabyte) {
  init();
  test::ScratchDir dir("vdb_tb");
  const auto grid = synthetic_grid();
  for (auto codec : {nanovdb::io::Codec::NONE, nanovdb::io::Codec::ZIP, nanovdb::io::Codec::BLOSC}) {
    const auto file = dir / "lie.nvdb";
    nanovdb::io::writeGrid(file.string(), nanovdb::openToNanoVDB(*grid), codec);
    const auto good = test::read_bytes(file);
    for (size_t field : {0, 8}) {  // MetaData::gridSize, MetaData::fileSize (after the 16-byte header)
      auto b = good;
      const uint64_t tb = uint64_t(1) << 40;
      std::memcpy(b.data() + 16 + field, &tb, 8);
      test::write_bytes(file, b);
      const std::string msg = test::load_error(file);
      EXPECT_NE(msg.find("lie.nvdb: "), std::string::npos) << msg;
    }
    // Bit flips all over a small file of each codec.
    std::mt19937_64 rng(14);
    for (int n = 0; n < 150; ++n) {
      auto b = good;
      const size_t at = std::uniform_int_distribution<size_t>(0, b.size() - 1)(rng);
      b[at] = static_cast<char>(b[at] ^ (1 << (rng() % 8)));
      test::write_bytes(file, b);
      try {
        const DensityGrid g = load_density_grid(file);
        (void)g.density_index(Vec3(1.5, 1.5, 1.5));
      } catch (const Error&) {
      }
    }
  }
}

}  // namespace
}  // namespace nimbus
