// nimbus convert IN.vdb OUT.nvdb: the NanoVDB file holds the same grids (same voxels, values, transform:
// `nimbus info` says the same) and renders the same image; bad conversions exit 2 with nothing written.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include "nimbus/image.h"
#include "support/cli.h"
#include "support/scratch_dir.h"

namespace nimbus {
namespace {

namespace fs = std::filesystem;

using test::run_cli;

std::string after_first_line(const std::string& s) { return s.substr(s.find('\n') + 1); }

TEST(ConvertCli, VdbBecomesAnEquivalentNvdb) {
  const test::ScratchDir dir("convert_vdb");
  const fs::path vdb = fs::path(NIMBUS_SOURCE_DIR) / "fuzz" / "data" / "tiny.vdb";
  ASSERT_EQ(run_cli("convert " + vdb.string() + " " + (dir / "t.nvdb").string()).rc, 0);
  const test::CliRun info_a = run_cli("info " + vdb.string()),
                     info_b = run_cli("info " + (dir / "t.nvdb").string());
  ASSERT_EQ(info_b.rc, 0) << info_b.out;
  const std::string &a = info_a.out, &b = info_b.out;
  EXPECT_EQ(after_first_line(a), after_first_line(b));
  EXPECT_NE(b.find("active voxels 25"), std::string::npos) << b;
  // The same image from either file.
  for (const char* f : {"a", "b"}) {
    test::write_vdb_scene(dir / (std::string(f) + ".json"),
                          f[0] == 'a' ? vdb.string() : (dir / "t.nvdb").string(), 8, 6,
                          R"({"type": "pathtrace", "spp": 2})");
    ASSERT_EQ(run_cli("render --quiet " + (dir / (std::string(f) + ".json")).string() + " -o " +
                      (dir / (std::string(f) + ".exr")).string())
                  .rc,
              0);
  }
  const Image ia = read_exr(dir / "a.exr"), ib = read_exr(dir / "b.exr");
  ASSERT_EQ(ia.rgb.size(), ib.rgb.size());
  EXPECT_EQ(0, std::memcmp(ia.rgb.data(), ib.rgb.data(), ia.rgb.size() * sizeof(float)));
  // Not a .vdb, no such grid, an image to a volume: exit 2 naming the file, nothing written.
  for (const std::string& bad : {"convert " + (dir / "a.exr").string() + " " + (dir / "x.nvdb").string(),
                                 "convert " + vdb.string() + " " + (dir / "x.nvdb").string() + " --grid nope",
                                 "convert " + (dir / "t.nvdb").string() + " " + (dir / "x.nvdb").string(),
                                 "convert " + vdb.string() + " " + (dir / "x.png").string()}) {
    const test::CliRun r = run_cli(bad);
    const std::string& err = r.out;
    EXPECT_EQ(r.rc, 2) << bad << ": " << err;
    EXPECT_NE(err.find("nimbus: error: "), std::string::npos) << err;
  }
  EXPECT_FALSE(fs::exists(dir / "x.nvdb"));
  EXPECT_FALSE(fs::exists(dir / "x.png"));
}

// --upsample N: a grid with voxels N times smaller (the field itself: tests/io/vdb_upsample_test.cpp);
// a factor outside [1, 16], or with an image, exits 2 with nothing written.
TEST(ConvertCli, UpsampleRefinesTheGridAndRefusesBadFactors) {
  const test::ScratchDir dir("convert_upsample");
  const fs::path vdb = fs::path(NIMBUS_SOURCE_DIR) / "fuzz" / "data" / "tiny.vdb";
  ASSERT_EQ(run_cli("convert " + vdb.string() + " " + (dir / "t3.nvdb").string() + " --upsample 3").rc, 0);
  const test::CliRun info = run_cli("info " + (dir / "t3.nvdb").string());
  EXPECT_NE(info.out.find("voxel size    0.166667 x 0.166667 x 0.166667"), std::string::npos) << info.out;
  for (const std::string& bad :
       {"convert " + vdb.string() + " " + (dir / "x.nvdb").string() + " --upsample 0",
        "convert " + vdb.string() + " " + (dir / "x.nvdb").string() + " --upsample 17",
        "convert " + vdb.string() + " " + (dir / "x.nvdb").string() + " --upsample two"}) {
    const test::CliRun r = run_cli(bad);
    EXPECT_EQ(r.rc, 2) << bad << ": " << r.out;
    EXPECT_NE(r.out.find("nimbus: error: --upsample"), std::string::npos) << r.out;
  }
  EXPECT_FALSE(fs::exists(dir / "x.nvdb"));
  // An image conversion takes no factor.
  test::write_vdb_scene(dir / "a.json", vdb.string(), 4, 3, R"({"type": "pathtrace", "spp": 1})");
  ASSERT_EQ(run_cli("render --quiet " + (dir / "a.json").string() + " -o " + (dir / "a.exr").string()).rc, 0);
  const test::CliRun r =
      run_cli("convert " + (dir / "a.exr").string() + " " + (dir / "x.png").string() + " --upsample 2");
  EXPECT_EQ(r.rc, 2) << r.out;
  EXPECT_NE(r.out.find("--upsample: only for a .vdb -> .nvdb conversion"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(dir / "x.png"));
}

}  // namespace
}  // namespace nimbus
