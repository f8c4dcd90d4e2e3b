// Command-line arguments found wanting by hand next to the CLI fuzz target, which only parses
// (docs/reliability.md): each must exit with code 2 and a message naming the option.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <tuple>

#include "nimbus/image.h"
#include "support/scratch_dir.h"

namespace nimbus {
namespace {

// Runs the CLI with `args`; returns (exit code, stderr).
std::pair<int, std::string> run_args(const std::string& args) {
  test::ScratchDir dir("cli_args");
  const std::string cmd =
      std::string(NIMBUS_CLI) + " " + args + " > /dev/null 2> " + (dir / "err.txt").string();
  const int status = std::system(cmd.c_str());
  std::ifstream err(dir / "err.txt");
  std::string text{std::istreambuf_iterator<char>(err), std::istreambuf_iterator<char>()};
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, text};
}

TEST(CliArgs, SlabExtinctionThatOverflowsIsRefused) {
  const auto [code, err] = run_args("slab --mu-s 1e308 --mu-a 1e308 --g 0.5 --thickness 1 --photons 20");
  EXPECT_EQ(code, 2);
  EXPECT_NE(err.find("--mu-s + --mu-a must be finite"), std::string::npos) << err;
}

// What a new user met (issue 13): each is now exit 2 with a message that says what is wrong.
TEST(CliArgs, ParserErrorsCarryThePrefix) {
  const auto [code, err] = run_args("render --bogus");
  EXPECT_EQ(code, 2);
  EXPECT_EQ(err.rfind("nimbus: error: ", 0), 0u) << err;
  EXPECT_NE(err.find("--bogus"), std::string::npos) << err;
}

TEST(CliArgs, OutputFolderIsNotAFormat) {
  const auto [code, err] = run_args("render -o /tmp/");
  EXPECT_EQ(code, 2);
  EXPECT_NE(err.find("names a folder, not a file"), std::string::npos) << err;
}

TEST(CliArgs, BeamAndSlabCheckTheirOutputBeforeTheWork) {
  // 1e9 photons would take minutes: the check comes first.
  auto [code, err] =
      run_args("beam --phase hg:0.9 --albedo 0.9 --depths 1 --photons 1e9 -o /nonexistent/x.csv");
  EXPECT_EQ(code, 2);
  EXPECT_NE(err.find("/nonexistent"), std::string::npos) << err;
  std::tie(code, err) =
      run_args("slab --mu-s 1 --mu-a 0.1 --g 0.5 --thickness 1 --photons 1e9 --csv /nonexistent/y.csv");
  EXPECT_EQ(code, 2);
  EXPECT_NE(err.find("--csv"), std::string::npos) << err;
}

TEST(CliArgs, VolumeOrBrokenJsonGivenAsTheScene) {
  test::ScratchDir dir("cli_args_scene");
  std::ofstream(dir / "cloud.vdb") << "not read";
  auto [code, err] = run_args("render " + (dir / "cloud.vdb").string() + " -o " + (dir / "a.exr").string());
  EXPECT_EQ(code, 2);
  EXPECT_NE(err.find("a volume, not a scene"), std::string::npos) << err;
  std::ofstream(dir / "bad.json") << "{\"camera\": {\n  \"width\": 3,,\n}}";
  std::tie(code, err) = run_args("render " + (dir / "bad.json").string() + " -o " + (dir / "a.exr").string());
  EXPECT_EQ(code, 2);
  EXPECT_NE(err.find("not valid JSON at line 2, column 14"), std::string::npos) << err;
  EXPECT_EQ(err.find("json.exception"), std::string::npos) << err;
}

TEST(CliArgs, SetAndResOverrideTheScene) {
  test::ScratchDir dir("cli_args_set");
  const std::string out = (dir / "a.exr").string();
  auto [code, err] =
      run_args("render --res 24x12 --set integrator.spp=1 --set integrator.type=single -o " + out);
  EXPECT_EQ(code, 0) << err;
  ImageMetadata meta;
  const Image img = read_exr(out, &meta);
  EXPECT_EQ(img.width, 24);
  EXPECT_EQ(img.height, 12);
  for (const auto& [k, v] : meta) {
    if (k == "nimbus/integrator") {
      EXPECT_EQ(v, "single");
    }
  }
  std::tie(code, err) = run_args("render --set media.3.sigma_s=1 -o " + (dir / "b.exr").string());
  EXPECT_EQ(code, 2);
  EXPECT_NE(err.find("--set media.3.sigma_s"), std::string::npos) << err;
  std::tie(code, err) = run_args("render --res 0x5 -o " + (dir / "b.exr").string());
  EXPECT_EQ(code, 2);
  EXPECT_NE(err.find("--res"), std::string::npos) << err;
  EXPECT_FALSE(std::filesystem::exists(dir / "b.exr"));
}

}  // namespace
}  // namespace nimbus
