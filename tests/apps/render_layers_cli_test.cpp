// nimbus render --layers / --deep end to end: the EXR's channels as OpenEXR lists them, the deep file,
// and bad options exiting 2 with the option named, before any output is written.
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "nimbus/image.h"
#include "support/scratch_dir.h"

namespace nimbus {
namespace {

namespace fs = std::filesystem;

void write_layers_scene(const fs::path& file) {
  std::ofstream(file) << R"({"camera": {"position": [0, -4, 0], "look_at": [0, 0, 0], "up": [0, 0, 1],
    "fov_y_deg": 30, "width": 8, "height": 8},
    "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": 5.0}],
    "lights": [{"type": "directional", "direction": [1, 1, -1], "irradiance": 2.0},
               {"type": "environment", "radiance": 0.1}],
    "integrator": {"type": "single", "spp": 2}})";
}

// Exit code of `nimbus ARGS`, stderr into *err.
int run_layers(const std::string& args, const fs::path& dir, std::string* err) {
  const fs::path log = dir / "stderr.txt";
  const int status = std::system((std::string(NIMBUS_CLI) + " " + args + " 2> " + log.string()).c_str());
  std::ostringstream text;
  text << std::ifstream(log).rdbuf();
  *err = text.str();
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(RenderLayersCli, LayersAndDeepFiles) {
  const test::ScratchDir dir("render_layers_cli");
  write_layers_scene(dir / "s.json");
  std::string err;
  ASSERT_EQ(run_layers("render " + (dir / "s.json").string() + " -o " + (dir / "a.exr").string() +
                           " --layers depth,normal,samples,indirect --deep " + (dir / "d.exr").string() +
                           " --deep-samples 4 --quiet",
                       dir.path, &err),
            0)
      << err;
  Imf::InputFile file((dir / "a.exr").c_str());
  std::vector<std::string> names;
  for (auto it = file.header().channels().begin(); it != file.header().channels().end(); ++it)
    names.push_back(it.name());
  EXPECT_EQ(names, (std::vector<std::string>{"A", "B", "G", "R", "Z", "indirect.B", "indirect.G",
                                             "indirect.R", "normal.X", "normal.Y", "normal.Z", "samples.X"}));
  // The header keeps the render's metadata and says what the film was.
  ImageMetadata meta;
  read_exr(dir / "a.exr", &meta);
  std::string scene;
  for (const auto& [k, v] : meta)
    if (k == "nimbus/scene") scene = v;
  EXPECT_NE(scene.find("\"layers\":[\"depth\",\"normal\",\"samples\",\"indirect\"]"), std::string::npos)
      << scene;
  const DeepImage deep = read_deep_exr(dir / "d.exr");
  EXPECT_EQ(deep.width, 8);
  for (size_t i = 0; i + 1 < deep.offsets.size(); ++i) EXPECT_LE(deep.offsets[i + 1] - deep.offsets[i], 4u);
  EXPECT_GT(deep.samples.size(), 0u);
}

TEST(RenderLayersCli, BadLayerOrDeepOptionsExitTwoNamingTheOption) {
  const test::ScratchDir dir("render_layers_bad");
  write_layers_scene(dir / "s.json");
  const std::string base = "render " + (dir / "s.json").string() + " --quiet -o ";
  std::string err;
  EXPECT_EQ(run_layers(base + (dir / "a.exr").string() + " --layers depth,zdepth", dir.path, &err), 2);
  EXPECT_NE(err.find("--layers"), std::string::npos) << err;
  EXPECT_EQ(run_layers(base + (dir / "a.png").string() + " --layers depth", dir.path, &err), 2);
  EXPECT_NE(err.find("--layers"), std::string::npos) << err;
  EXPECT_EQ(
      run_layers(base + (dir / "a.exr").string() + " --deep " + (dir / "d.png").string(), dir.path, &err), 2);
  EXPECT_NE(err.find("--deep"), std::string::npos) << err;
  EXPECT_EQ(run_layers(
                base + (dir / "a.exr").string() + " --deep " + (dir / "d.exr").string() + " --deep-samples 0",
                dir.path, &err),
            2);
  EXPECT_NE(err.find("--deep-samples"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(dir / "a.exr"));
  EXPECT_FALSE(fs::exists(dir / "a.png"));
}

}  // namespace
}  // namespace nimbus
