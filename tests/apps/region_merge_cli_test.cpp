// render --region and --samples, and nimbus merge, end to end: a crop's pixels and film sums equal the
// full render's bit for bit, tiles merge into the full render bit for bit, sample ranges merge into the
// render of all their samples bit for bit (docs/cli.md), and every bad input exits 2 naming
// the option or the file and the header field, with nothing written.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
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

void write_merge_scene(const fs::path& file, int spp) {
  std::ofstream(file) << R"({"camera": {"position": [0, -4, 0], "look_at": [0, 0, 0], "up": [0, 0, 1],
    "fov_y_deg": 30, "width": 14, "height": 10},
    "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": 5.0,
               "phase": {"type": "hg", "g": 0.7}}],
    "lights": [{"type": "directional", "direction": [1, 1, -1], "irradiance": 2.0},
               {"type": "environment", "radiance": 0.1}],
    "film": {"layers": ["depth", "direct"]},
    "integrator": {"type": "pathtrace", "spp": )"
                      << spp << "}}";
}

using test::meta_value;
using test::run_cli_status;
using test::slurp;

bool same_bits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// Every pixel of `crop` (at its origin) against the same pixel of `full`: RGB, A and film sums, bit for bit.
void expect_crop_of(const fs::path& crop_file, const fs::path& full_file) {
  const Image crop = read_exr(crop_file), full = read_exr(full_file);
  const FilmState cs = read_exr_state(crop_file), fs_ = read_exr_state(full_file);
  ASSERT_EQ(cs.layers.size(), fs_.layers.size());
  int64_t compared = 0;
  for (int y = 0; y < crop.height; ++y)
    for (int x = 0; x < crop.width; ++x) {
      const size_t c = size_t(y) * crop.width + x;
      const size_t f = size_t(y + crop.origin_y) * full.width + size_t(x + crop.origin_x);
      for (int k = 0; k < 3; ++k)
        ASSERT_TRUE(same_bits(crop.rgb[3 * c + k], full.rgb[3 * f + k])) << x << "," << y;
      ASSERT_TRUE(same_bits(crop.alpha[c], full.alpha[f]));
      for (size_t l = 0; l < cs.layers.size(); ++l) {
        const int n = cs.layers[l].channels;
        for (int k = 0; k < n; ++k)
          ASSERT_TRUE(cs.layers[l].sums[n * c + k] == fs_.layers[l].sums[n * f + k]) << cs.layers[l].name;
      }
      ++compared;
    }
  EXPECT_GT(compared, 0);
}

TEST(RegionCli, CropEqualsTheFullRenderBitForBit) {
  const test::ScratchDir dir("region_crop");
  write_merge_scene(dir / "s.json", 3);
  const std::string s = (dir / "s.json").string() + " --quiet ";
  ASSERT_EQ(run_cli_status("render " + s + "-o " + (dir / "full.exr").string()), 0);
  // An odd window, on one thread with small tiles: neither the tiling nor the threads matter.
  ASSERT_EQ(run_cli_status("render " + s + "--region 3,2,12,9 --threads 1 -o " + (dir / "crop.exr").string()),
            0);
  ImageMetadata meta;
  const Image crop = read_exr(dir / "crop.exr", &meta);
  EXPECT_EQ(crop.width, 9);
  EXPECT_EQ(crop.height, 7);
  EXPECT_EQ(crop.origin_x, 3);
  EXPECT_EQ(crop.origin_y, 2);
  EXPECT_EQ(crop.display_width, 14);
  EXPECT_EQ(crop.display_height, 10);
  EXPECT_EQ(meta_value(meta, "nimbus/region"), "3,2,12,9");
  expect_crop_of(dir / "crop.exr", dir / "full.exr");
  // A crop resumed to more samples is the crop of the render with as many.
  ASSERT_EQ(run_cli_status("render " + s + "--region 0,5,14,10 --spp 1 -o " + (dir / "r.exr").string()), 0);
  ASSERT_EQ(run_cli_status("render --quiet --resume " + (dir / "r.exr").string() + " --spp 3"), 0);
  expect_crop_of(dir / "r.exr", dir / "full.exr");
}

TEST(RegionCli, WindowOutsideTheImageIsRejected) {
  const test::ScratchDir dir("region_bad");
  write_merge_scene(dir / "s.json", 1);
  const std::string s = "render " + (dir / "s.json").string() + " --quiet -o " + (dir / "x.exr").string();
  for (const char* bad :
       {"0,0,15,10", "0,0,14,11", "5,5,5,8", "4,4,2,8", "-1,0,4,4", "1,2,3", "a,b,c,d", "0,0,4,4,5"}) {
    EXPECT_EQ(run_cli_status(s + " --region " + bad + " 2>" + (dir / "err.txt").string()), 2) << bad;
    EXPECT_NE(slurp(dir / "err.txt").find("--region"), std::string::npos)
        << bad << ": " << slurp(dir / "err.txt");
  }
  // After --res the window is checked against the new size.
  EXPECT_EQ(run_cli_status(s + " --res 8x8 --region 0,0,10,8 2>/dev/null"), 2);
  EXPECT_FALSE(fs::exists(dir / "x.exr"));
}

TEST(MergeCli, TilesAssembleIntoTheFullRenderBitForBit) {
  const test::ScratchDir dir("merge_tiles");
  write_merge_scene(dir / "s.json", 2);
  const std::string s = "render " + (dir / "s.json").string() + " --quiet ";
  ASSERT_EQ(run_cli_status(s + "-o " + (dir / "full.exr").string()), 0);
  const char* tiles[] = {"0,0,5,4", "5,0,14,4", "0,4,9,10", "9,4,14,10"};
  std::string inputs;
  for (int i = 0; i < 4; ++i) {
    const std::string t = (dir / ("t" + std::to_string(i) + ".exr")).string();
    ASSERT_EQ(run_cli_status(s + "--region " + tiles[i] + " -o " + t), 0);
    inputs += t + " ";
  }
  ASSERT_EQ(run_cli_status("merge --quiet " + inputs + "-o " + (dir / "m.exr").string()), 0);
  ImageMetadata mm, fm;
  const Image m = read_exr(dir / "m.exr", &mm), full = read_exr(dir / "full.exr", &fm);
  EXPECT_EQ(m.display_width, 0);  // the whole frame
  expect_crop_of(dir / "m.exr", dir / "full.exr");
  EXPECT_EQ(meta_value(mm, "nimbus/scene"), meta_value(fm, "nimbus/scene"));
  EXPECT_EQ(meta_value(mm, "nimbus/spp"), "2");
  // Two tiles make a crop of their bounding box; a missing one leaves a gap: exit 2, nothing written.
  ASSERT_EQ(run_cli_status("merge --quiet " + (dir / "t0.exr").string() + " " + (dir / "t1.exr").string() +
                           " -o " + (dir / "top.exr").string()),
            0);
  EXPECT_EQ(read_exr(dir / "top.exr").height, 4);
  expect_crop_of(dir / "top.exr", dir / "full.exr");
  EXPECT_EQ(run_cli_status("merge " + (dir / "t0.exr").string() + " " + (dir / "t3.exr").string() + " -o " +
                           (dir / "gap.exr").string() + " 2>" + (dir / "err.txt").string()),
            2);
  EXPECT_NE(slurp(dir / "err.txt").find("in no input"), std::string::npos) << slurp(dir / "err.txt");
  EXPECT_FALSE(fs::exists(dir / "gap.exr"));
}

TEST(MergeCli, SampleRangesAddUpToTheRenderOfAllSamples) {
  const test::ScratchDir dir("merge_samples");
  write_merge_scene(dir / "s.json", 5);
  const std::string s = "render " + (dir / "s.json").string() + " --quiet ";
  ASSERT_EQ(run_cli_status(s + "-o " + (dir / "full.exr").string()), 0);
  ASSERT_EQ(run_cli_status(s + "--samples 0:5 -o " + (dir / "all.exr").string()),
            0);  // START 0: the plain render
  expect_crop_of(dir / "all.exr", dir / "full.exr");
  ASSERT_EQ(run_cli_status(s + "--samples 0:2 -o " + (dir / "a.exr").string()), 0);
  ASSERT_EQ(run_cli_status(s + "--samples 2:3 --threads 1 -o " + (dir / "b.exr").string()), 0);
  // A range resumed to more samples keeps its start: the same as the range rendered in one go.
  ASSERT_EQ(run_cli_status(s + "--samples 2:1 -o " + (dir / "b1.exr").string()), 0);
  ASSERT_EQ(run_cli_status("render --quiet --resume " + (dir / "b1.exr").string() + " --spp 3"), 0);
  expect_crop_of(dir / "b1.exr", dir / "b.exr");
  ImageMetadata bm;
  read_exr(dir / "b.exr", &bm);
  EXPECT_EQ(meta_value(bm, "nimbus/sample_start"), "2");
  EXPECT_EQ(meta_value(bm, "nimbus/spp"), "3");
  // Given in any order; a tile of the second range beside the whole-frame first range works as well.
  ASSERT_EQ(run_cli_status("merge --quiet " + (dir / "b.exr").string() + " " + (dir / "a.exr").string() +
                           " -o " + (dir / "m.exr").string()),
            0);
  ImageMetadata mm, fm;
  const Image m = read_exr(dir / "m.exr", &mm), full = read_exr(dir / "full.exr", &fm);
  EXPECT_EQ(meta_value(mm, "nimbus/spp"), "5");
  EXPECT_EQ(meta_value(mm, "nimbus/sample_start"), "0");
  EXPECT_EQ(meta_value(mm, "nimbus/scene"), meta_value(fm, "nimbus/scene"));
  EXPECT_EQ(meta_value(mm, "nimbus/integrator_settings"), meta_value(fm, "nimbus/integrator_settings"));
  // The merge adds the two ranges' fixed-point sums, the one render added sample by sample: equal to
  // the bit (render/film.h), the pixels and every sum.
  expect_crop_of(dir / "m.exr", dir / "full.exr");
  EXPECT_EQ(read_exr_state(dir / "m.exr").counts, read_exr_state(dir / "full.exr").counts);
  EXPECT_EQ(0, std::memcmp(m.rgb.data(), full.rgb.data(), m.rgb.size() * sizeof(float)));
  // The power check: ranges that differ from the whole render.
  EXPECT_NE(0,
            std::memcmp(read_exr(dir / "a.exr").rgb.data(), full.rgb.data(), m.rgb.size() * sizeof(float)));
}

TEST(MergeCli, IncompatibleInputsAreRefusedNamingFileAndField) {
  const test::ScratchDir dir("merge_bad");
  write_merge_scene(dir / "s.json", 2);
  const std::string s = "render " + (dir / "s.json").string() + " --quiet ";
  ASSERT_EQ(run_cli_status(s + "--samples 0:2 -o " + (dir / "a.exr").string()), 0);
  struct Case {
    std::string render, field;
  } cases[] = {{"--samples 2:2 --seed 9", "nimbus/seed"},
               {"--samples 2:2 --set media.0.sigma_s=4", "nimbus/scene (media)"},
               {"--samples 2:2 --integrator single", "nimbus/integrator"},
               {"--samples 2:2 --res 14x12", "nimbus/scene (camera)"},
               {"--samples 2:2 --layers depth", "nimbus/scene (film)"},
               {"--samples 1:2", "overlap"},
               {"--samples 3:2", "do not follow"}};
  int i = 0;
  for (const Case& c : cases) {
    const std::string b = (dir / ("b" + std::to_string(i++) + ".exr")).string();
    ASSERT_EQ(run_cli_status(s + c.render + " -o " + b), 0) << c.render;
    EXPECT_EQ(run_cli_status("merge " + (dir / "a.exr").string() + " " + b + " -o " +
                             (dir / "m.exr").string() + " 2>" + (dir / "err.txt").string()),
              2)
        << c.render;
    const std::string err = slurp(dir / "err.txt");
    EXPECT_NE(err.find(c.field), std::string::npos) << c.render << ": " << err;
    EXPECT_NE(err.find("nimbus: error: "), std::string::npos) << err;
    EXPECT_NE(err.find(".exr"), std::string::npos) << err;
    EXPECT_FALSE(fs::exists(dir / "m.exr")) << c.render;
  }
}

TEST(MergeCli, NonRendersAndBadSampleRangesAreRefused) {
  const test::ScratchDir dir("merge_bad_ranges");
  write_merge_scene(dir / "s.json", 2);
  const std::string s = "render " + (dir / "s.json").string() + " --quiet ";
  ASSERT_EQ(run_cli_status(s + "--samples 0:2 -o " + (dir / "a.exr").string()), 0);
  // Not a nimbus render, --samples beside --spp, a bad range: exit 2.
  write_exr(dir / "plain.exr", read_exr(dir / "a.exr"));
  EXPECT_EQ(run_cli_status("merge " + (dir / "a.exr").string() + " " + (dir / "plain.exr").string() + " -o " +
                           (dir / "m.exr").string() + " 2>/dev/null"),
            2);
  EXPECT_EQ(run_cli_status(s + "--samples 0:2 --spp 2 -o " + (dir / "m.exr").string() + " 2>/dev/null"), 2);
  for (const char* bad : {"2", "0:0", "-1:2", "1:x", "0:2:3"})
    EXPECT_EQ(run_cli_status(s + "--samples " + std::string(bad) + " -o " + (dir / "m.exr").string() +
                             " 2>/dev/null"),
              2)
        << bad;
  EXPECT_FALSE(fs::exists(dir / "m.exr"));
}

}  // namespace
}  // namespace nimbus
