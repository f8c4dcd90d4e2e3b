// `nimbus compare` run as a user would: JSON metrics and a heat map, and a missing file named with exit code 2.
#include <gtest/gtest.h>
#include <sys/wait.h>

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

}  // namespace
}  // namespace nimbus
