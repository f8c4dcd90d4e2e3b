// nimbus render --time-bins / film.time_bins end to end: OUT.time.exr beside the image with the bins as
// layers (as OpenEXR lists them), the image itself unchanged; bad bins and other integrators exit 2
// naming the field, before any output is written.
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>

#include "nimbus/image.h"
#include "support/cli.h"
#include "support/scratch_dir.h"

namespace nimbus {
namespace {

namespace fs = std::filesystem;

void write_transient_scene(const fs::path& file) {
  std::ofstream(file) << R"({"camera": {"position": [0, -4, 0], "look_at": [0, 0, 0], "up": [0, 0, 1],
    "fov_y_deg": 30, "width": 8, "height": 6},
    "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": 3.0}],
    "lights": [{"type": "point", "position": [1.5, -1.5, 1], "intensity": 4.0},
               {"type": "environment", "radiance": 0.1}],
    "integrator": {"type": "pathtrace", "spp": 4}})";
}

TEST(CliTransient, WritesTheBinsBesideAnUnchangedImage) {
  const test::ScratchDir dir("cli_transient");
  write_transient_scene(dir / "s.json");
  const std::string scene = (dir / "s.json").string();
  const test::CliRun plain =
      test::run_cli("render " + scene + " -o " + (dir / "plain.exr").string() + " --quiet");
  ASSERT_EQ(plain.rc, 0) << plain.out;
  EXPECT_FALSE(fs::exists(dir / "plain.time.exr"));
  const test::CliRun timed =
      test::run_cli("render " + scene + " -o " + (dir / "t.exr").string() + " --time-bins 2,8,12 --quiet");
  ASSERT_EQ(timed.rc, 0) << timed.out;
  const Image a = read_exr(dir / "plain.exr"), b = read_exr(dir / "t.exr");
  ASSERT_EQ(a.rgb.size(), b.rgb.size());
  EXPECT_EQ(0, std::memcmp(a.rgb.data(), b.rgb.data(), a.rgb.size() * sizeof(float)));
  Imf::InputFile file((dir / "t.time.exr").c_str());
  int layers = 0;
  for (auto it = file.header().channels().begin(); it != file.header().channels().end(); ++it)
    layers += std::strncmp(it.name(), "time", 4) == 0;
  EXPECT_EQ(layers, 3 * 14);
  for (const char* c : {"R", "A", "time0000.R", "time0011.B", "time_under.G", "time_over.R"})
    EXPECT_NE(file.header().channels().findChannel(c), nullptr) << c;
  const auto* bins = file.header().findTypedAttribute<Imf::StringAttribute>("nimbus/time_bins");
  ASSERT_NE(bins, nullptr);
  EXPECT_EQ(bins->value(), "2,8,12");
}

TEST(CliTransient, BadBinsExitTwoNamingTheFieldAndWriteNothing) {
  const test::ScratchDir dir("cli_transient_bad");
  write_transient_scene(dir / "s.json");
  const std::string scene = (dir / "s.json").string(), out = (dir / "o.exr").string();
  for (const std::string bins : {"", "8,2,4", "-1,2,4", "0,2,0", "0,2", "0,2,x", "0,1,100000000"}) {
    SCOPED_TRACE(bins);
    const test::CliRun r =
        test::run_cli("render " + scene + " -o " + out + " --time-bins '" + bins + "' --quiet");
    EXPECT_EQ(r.rc, 2) << r.out;
    EXPECT_NE(r.out.find("time_bins"), std::string::npos) << r.out;
  }
  // Too much memory for the image size, and another integrator.
  const test::CliRun big =
      test::run_cli("render " + scene + " -o " + out + " --res 4000x4000 --time-bins 0,1,10000 --quiet");
  EXPECT_EQ(big.rc, 2) << big.out;
  EXPECT_NE(big.out.find("GiB"), std::string::npos) << big.out;
  const test::CliRun single =
      test::run_cli("render " + scene + " -o " + out + " --integrator single --time-bins 0,8,4 --quiet");
  EXPECT_EQ(single.rc, 2) << single.out;
  EXPECT_NE(single.out.find("film.time_bins"), std::string::npos) << single.out;
  EXPECT_FALSE(fs::exists(dir / "o.exr"));
  EXPECT_FALSE(fs::exists(dir / "o.time.exr"));
}

}  // namespace
}  // namespace nimbus
