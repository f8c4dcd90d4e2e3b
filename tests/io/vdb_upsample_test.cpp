// Upsampling a grid (nimbus convert --upsample N, io/vdb_upsample.h): the fine grid is the same trilinear
// density field as the coarse one (closed form: a piecewise-trilinear field restricted to finer cells),
// a single voxel becomes the tent it spans, and bad factors or sizes are errors naming the file.
#include "io/vdb_upsample.h"

#include <gtest/gtest.h>
#include <nanovdb/util/OpenToNanoVDB.h>
#include <openvdb/io/File.h>

#include <cmath>
#include <random>

#include "io/vdb.h"
#include "io/vdb_convert.h"
#include "io/vdb_test_util.h"
#include "nimbus/error.h"

namespace nimbus {
namespace {

void init_openvdb() {
  static bool done = (openvdb::initialize(), true);
  (void)done;
}

DensityGrid density_grid(const openvdb::FloatGrid& grid) {
  return DensityGrid::from_nanovdb(nanovdb::openToNanoVDB(grid), "test grid");
}

// Random values, some negative (clamped when sampled), an inactive non-zero leaf value (sampled too), an
// active tile, and a map with scale and translation.
openvdb::FloatGrid::Ptr lumpy_grid() {
  auto grid = openvdb::FloatGrid::create(0.0f);
  grid->setName("density");
  auto xform = openvdb::math::Transform::createLinearTransform(0.5);
  xform->postTranslate(openvdb::Vec3d(1.0, -2.0, 3.0));
  grid->setTransform(xform);
  auto acc = grid->getAccessor();
  std::mt19937_64 rng(21);
  std::uniform_real_distribution<float> u(-0.3f, 2.0f);
  for (int i = -5; i < 9; ++i)
    for (int j = 0; j < 7; ++j)
      for (int k = -3; k < 4; ++k) acc.setValueOn(openvdb::Coord(i, j, k), u(rng));
  acc.setValueOff(openvdb::Coord(2, 2, 2), 0.75f);
  grid->tree().addTile(1, openvdb::Coord(16, 0, 0), 1.5f, /*active=*/true);
  return grid;
}

TEST(VdbUpsample, TheFineGridIsTheSameField) {
  init_openvdb();
  const auto coarse_vdb = lumpy_grid();
  const DensityGrid coarse = density_grid(*coarse_vdb);
  const Bounds wb = coarse.world_bounds();
  for (const int factor : {2, 3}) {
    const auto fine_vdb = detail::upsample_float_grid(*coarse_vdb, factor);
    EXPECT_EQ(fine_vdb->getName(), "density");
    const DensityGrid fine = density_grid(*fine_vdb);
    EXPECT_NEAR(fine.stats().voxel_size.x, 0.5 / factor, 1e-12);
    std::mt19937_64 rng(22);
    std::uniform_real_distribution<double> u(-0.1, 1.1);
    int nonzero = 0;
    for (int n = 0; n < 20000; ++n) {
      const Vec3 w(wb.lo.x + u(rng) * (wb.hi.x - wb.lo.x), wb.lo.y + u(rng) * (wb.hi.y - wb.lo.y),
                   wb.lo.z + u(rng) * (wb.hi.z - wb.lo.z));
      const double expected = coarse.density_index(coarse.world_to_index(w));
      ASSERT_NEAR(fine.density_index(fine.world_to_index(w)), expected, 1e-5 * (1.0 + expected))
          << "factor " << factor << " at " << w;
      nonzero += expected > 0.0;
    }
    EXPECT_GT(nonzero, 5000);  // the comparison is not vacuous
    // The core of the tile (value 1.5 well inside it) became tiles, not leaves.
    EXPECT_GT(fine_vdb->tree().activeTileCount(), 0u);
  }
}

TEST(VdbUpsample, OneVoxelBecomesItsTent) {
  init_openvdb();
  auto grid = openvdb::FloatGrid::create(0.0f);
  grid->tree().setValueOn(openvdb::Coord(0, 0, 0), 1.0f);
  const int f = 4;
  const auto fine = detail::upsample_float_grid(*grid, f);
  // The trilinear field of one voxel is prod(1 - |x|) on (-1, 1)^3: non-zero at the (2f - 1)^3 fine
  // voxels with |i| < f per axis.
  EXPECT_EQ(fine->activeVoxelCount(), uint64_t((2 * f - 1) * (2 * f - 1) * (2 * f - 1)));
  auto acc = fine->getConstAccessor();
  for (int i = -f; i <= f; ++i)
    for (int j = -f; j <= f; ++j) {
      const int k = (i + 2 * j) % f;
      const double expected =
          (1.0 - std::abs(i) / double(f)) * (1.0 - std::abs(j) / double(f)) * (1.0 - std::abs(k) / double(f));
      EXPECT_NEAR(acc.getValue(openvdb::Coord(i, j, k)), expected, 1e-6) << i << " " << j << " " << k;
    }
  EXPECT_NEAR(fine->voxelSize()[0], 1.0 / f, 1e-12);
  EXPECT_EQ(detail::upsampled_bbox_voxels(*grid, f), uint64_t((2 * f + 1) * (2 * f + 1) * (2 * f + 1)));
}

TEST(VdbUpsample, ConvertWritesTheFineGridAndRefusesBadFactors) {
  init_openvdb();
  test::ScratchDir dir("vdb_upsample");
  {
    openvdb::io::File file((dir / "lumpy.vdb").string());
    file.write({lumpy_grid()});
  }
  convert_vdb_to_nvdb(dir / "lumpy.vdb", dir / "fine.nvdb", {}, 2);
  EXPECT_NEAR(load_density_grid(dir / "fine.nvdb").stats().voxel_size.x, 0.25, 1e-12);
  for (const int bad : {0, -1, detail::kMaxUpsample + 1}) {
    try {
      convert_vdb_to_nvdb(dir / "lumpy.vdb", dir / "bad.nvdb", {}, bad);
      ADD_FAILURE() << "factor " << bad << " accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("lumpy.vdb: upsampling grid \"density\" by"), std::string::npos)
          << e.what();
    }
  }
  // Two voxels 1200 apart per axis: a 1.7e9-voxel bbox is accepted, the same upsampled by 2 is not
  // (refused before any fine voxel is written).
  auto wide = openvdb::FloatGrid::create(0.0f);
  wide->setName("density");
  wide->tree().setValueOn(openvdb::Coord(-600, -600, -600), 1.0f);
  wide->tree().setValueOn(openvdb::Coord(599, 599, 599), 1.0f);
  {
    openvdb::io::File file((dir / "wide.vdb").string());
    file.write({wide});
  }
  try {
    convert_vdb_to_nvdb(dir / "wide.vdb", dir / "bad.nvdb", {}, 2);
    ADD_FAILURE() << "a 1.4e10-voxel bbox accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("wide.vdb: upsampling grid \"density\" by 2 gives an index bbox"),
              std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "bad.nvdb"));
}

}  // namespace
}  // namespace nimbus
