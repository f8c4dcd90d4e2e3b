// `nimbus compare` run as a user would: JSON metrics and a heat map, and a missing file named with exit code 2.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "nimbus/image.h"
#include "support/scratch_dir.h"

namespace nimbus {
namespace {

namespace fs = std::filesystem;

TEST(CompareCli, PrintsJsonAndNamesMissingFiles) {
  const test::ScratchDir scratch("image_cli");
  const fs::path& dir = scratch.path;
  Image b(4, 4), a(4, 4);
  for (size_t i = 0; i < b.rgb.size(); ++i) {
    b.rgb[i] = 2.0f;
    a.rgb[i] = 2.5f;
  }
  write_exr(dir / "a.exr", a);
  write_exr(dir / "b.exr", b);
  const std::string cli = NIMBUS_CLI;
  const std::string cmd = cli + " compare " + (dir / "a.exr").string() + " " + (dir / "b.exr").string() +
                          " --json --heatmap " + (dir / "h.png").string() + " > " +
                          (dir / "out.json").string();
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  std::ifstream in(dir / "out.json");
  const auto j = nlohmann::json::parse(in);
  EXPECT_NEAR(j["mean_rel_error"].get<double>(), 0.25, 1e-6);
  EXPECT_TRUE(fs::exists(dir / "h.png"));
  const int status = std::system((cli + " compare " + (dir / "nope.exr").string() + " " +
                                  (dir / "b.exr").string() + " 2> " + (dir / "err.txt").string())
                                     .c_str());
  EXPECT_EQ(WEXITSTATUS(status), 2);
  std::ifstream err(dir / "err.txt");
  std::string line;
  std::getline(err, line);
  EXPECT_EQ(line, "nimbus: error: " + (dir / "nope.exr").string() + ": no such file");
}

TEST(CompareCli, HeatmapHasAColourBarLegend) {
  const test::ScratchDir scratch("heatmap_legend");
  const fs::path& dir = scratch.path;
  Image b(4, 4), a(4, 4);
  std::fill(b.rgb.begin(), b.rgb.end(), 2.0f);
  std::fill(a.rgb.begin(), a.rgb.end(), 2.5f);  // +25 %: half way to the +50 % of full red
  write_exr(dir / "a.exr", a);
  write_exr(dir / "b.exr", b);
  ASSERT_EQ(std::system((std::string(NIMBUS_CLI) + " compare " + (dir / "a.exr").string() + " " +
                         (dir / "b.exr").string() + " --heatmap " + (dir / "h.exr").string() + " > /dev/null")
                            .c_str()),
            0);
  const Image h = read_exr(dir / "h.exr");
  ASSERT_EQ(h.width, 64);  // padded so that the labels fit
  ASSERT_GT(h.height, 4 + 10);
  EXPECT_FLOAT_EQ(h.pixel(0, 0)[0], 1.0f);
  EXPECT_FLOAT_EQ(h.pixel(0, 0)[1], 0.5f);
  EXPECT_FLOAT_EQ(h.pixel(10, 0)[0], 0.0f);  // padding
  // The bar (2 pixels under the heatmap): blue at the left end, white in the middle, red at the right.
  const float* left = h.pixel(2, 6);
  const float* mid = h.pixel(32, 6);
  const float* right = h.pixel(61, 6);
  EXPECT_LT(left[0], 0.1f);
  EXPECT_FLOAT_EQ(left[2], 1.0f);
  EXPECT_GT(mid[0], 0.95f);
  EXPECT_GT(mid[1], 0.95f);
  EXPECT_GT(mid[2], 0.95f);
  EXPECT_FLOAT_EQ(right[0], 1.0f);
  EXPECT_LT(right[2], 0.1f);
  // Labels below the bar: white text on black.
  int white = 0, black = 0;
  for (int y = 13; y < h.height; ++y)
    for (int x = 0; x < h.width; ++x) (h.pixel(x, y)[1] == 1.0f ? white : black) += 1;
  EXPECT_GT(white, 20);
  EXPECT_GT(black, white);
}

}  // namespace
}  // namespace nimbus
