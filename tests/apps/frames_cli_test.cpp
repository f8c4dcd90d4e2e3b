// render --frames end to end: a sequence of volumes rendered frame by frame, $F / $F4 replaced in the
// scene's file names and in -o; each frame equals the single render of its file; bad lists and outputs
// without a frame number exit 2 with nothing written.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "nimbus/image.h"
#include "support/cli.h"
#include "support/scratch_dir.h"

namespace nimbus {
namespace {

namespace fs = std::filesystem;

void write_vdb_scene(const fs::path& file, const std::string& volume) {
  test::write_vdb_scene(file, volume, 10, 8, R"({"type": "pathtrace", "spp": 2})",
                        R"(, {"type": "environment", "radiance": 0.2})");
}

using test::meta_value;
using test::run_cli_status;
using test::slurp;

bool same_pixels(const Image& a, const Image& b) {
  return a.rgb.size() == b.rgb.size() && a.alpha.size() == b.alpha.size() &&
         std::memcmp(a.rgb.data(), b.rgb.data(), a.rgb.size() * sizeof(float)) == 0 &&
         std::memcmp(a.alpha.data(), b.alpha.data(), a.alpha.size() * sizeof(float)) == 0;
}

TEST(FramesCli, SequenceRendersEachFrameFromItsOwnFiles) {
  const test::ScratchDir dir("frames_seq");
  for (const char* name : {"cloud.0001.vdb", "cloud.0002.vdb", "cloud.0003.vdb"})
    fs::copy_file(fs::path(NIMBUS_SOURCE_DIR) / "fuzz" / "data" / "tiny.vdb", dir / name);
  write_vdb_scene(dir / "seq.json", "cloud.$F4.vdb");
  fs::create_directories(dir / "out");
  ASSERT_EQ(run_cli_status("render " + (dir / "seq.json").string() + " --quiet --frames 1-3 -o '" +
                           (dir / "out" / "f.$F4.exr").string() + "' --preview '" +
                           (dir / "out" / "p$F.png").string() + "'"),
            0);
  for (int f = 1; f <= 3; ++f) {
    const std::string pad = "000" + std::to_string(f);
    ImageMetadata meta;
    const Image frame = read_exr(dir / "out" / ("f." + pad + ".exr"), &meta);
    EXPECT_TRUE(fs::exists(dir / "out" / ("p" + std::to_string(f) + ".png")));
    EXPECT_EQ(meta_value(meta, "nimbus/frame"), std::to_string(f));
    EXPECT_NE(meta_value(meta, "nimbus/scene").find("cloud." + pad + ".vdb"), std::string::npos);
    // The same as the render of a scene that names the frame's file.
    write_vdb_scene(dir / "one.json", "cloud." + pad + ".vdb");
    ASSERT_EQ(
        run_cli_status("render " + (dir / "one.json").string() + " --quiet -o " + (dir / "one.exr").string()),
        0);
    EXPECT_TRUE(same_pixels(frame, read_exr(dir / "one.exr"))) << f;
  }
  // Every 2nd frame, and a list; $F in a --set value too.
  write_vdb_scene(dir / "plain.json", "none.vdb");
  ASSERT_EQ(
      run_cli_status("render " + (dir / "plain.json").string() + " --quiet --frames 1-3x2 --set " +
                     "'media.0.shape.file=cloud.$F4.vdb' -o '" + (dir / "out" / "s$F.exr").string() + "'"),
      0);
  EXPECT_TRUE(fs::exists(dir / "out" / "s1.exr"));
  EXPECT_FALSE(fs::exists(dir / "out" / "s2.exr"));
  EXPECT_TRUE(fs::exists(dir / "out" / "s3.exr"));
  // A missing frame file stops the sequence there, naming it: exit 2, the frames before it written.
  fs::remove(dir / "cloud.0002.vdb");
  EXPECT_EQ(run_cli_status("render " + (dir / "seq.json").string() + " --quiet --frames 1,2,3 -o '" +
                           (dir / "out" / "m$F.exr").string() + "' 2>" + (dir / "err.txt").string()),
            2);
  EXPECT_NE(slurp(dir / "err.txt").find("cloud.0002.vdb"), std::string::npos) << slurp(dir / "err.txt");
  EXPECT_TRUE(fs::exists(dir / "out" / "m1.exr"));
  EXPECT_FALSE(fs::exists(dir / "out" / "m2.exr"));
  EXPECT_FALSE(fs::exists(dir / "out" / "m3.exr"));
}

TEST(FramesCli, BadListsAndOutputsWithoutAFrameNumberAreRejected) {
  const test::ScratchDir dir("frames_bad");
  fs::copy_file(fs::path(NIMBUS_SOURCE_DIR) / "fuzz" / "data" / "tiny.vdb", dir / "c1.vdb");
  write_vdb_scene(dir / "s.json", "c$F.vdb");
  const std::string s = "render " + (dir / "s.json").string() + " --quiet ";
  for (const char* bad :
       {"", "3-1", "1-", "-3", "a", "1-5x0", "1,,2", "1,1", "1-3,2", "1x2", "1-3y2", "0-100000000"}) {
    EXPECT_EQ(run_cli_status(s + "--frames '" + bad + "' -o '" + (dir / "f$F.exr").string() + "' 2>" +
                             (dir / "err.txt").string()),
              2)
        << bad;
    EXPECT_NE(slurp(dir / "err.txt").find("--frames"), std::string::npos)
        << bad << ": " << slurp(dir / "err.txt");
  }
  EXPECT_EQ(
      run_cli_status(s + "--frames 1 -o " + (dir / "same.exr").string() + " 2>" + (dir / "err.txt").string()),
      2);
  EXPECT_NE(slurp(dir / "err.txt").find("$F"), std::string::npos) << slurp(dir / "err.txt");
  EXPECT_EQ(run_cli_status(s + "--frames 1 -o '" + (dir / "f$F.tif").string() + "' 2>/dev/null"), 2);
  for (const auto& e : fs::directory_iterator(dir.path)) EXPECT_NE(e.path().extension(), ".exr") << e.path();
}

}  // namespace
}  // namespace nimbus
