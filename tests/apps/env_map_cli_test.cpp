// nimbus render with an environment image: a good image renders (relative to the scene file) and the
// camera sees it; a missing file, a PNG and `file` with `radiance` exit 2 naming the file and the field,
// writing nothing.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <filesystem>
#include <fstream>

#include "nimbus/image.h"
#include "support/scratch_dir.h"

namespace nimbus {
namespace {

namespace fs = std::filesystem;

// Runs the CLI with stderr into `err`; returns its exit status.
int run_env(const std::string& args, const fs::path& err) {
  const int status = std::system((std::string(NIMBUS_CLI) + " " + args + " 2> " + err.string()).c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

void write_env_scene(const fs::path& file, const std::string& light) {
  std::ofstream(file) << R"({"camera": {"position": [0, -4, 0], "look_at": [0, 0, 0], "up": [0, 0, 1],
    "fov_y_deg": 30, "width": 8, "height": 8}, "media": [], "lights": [)"
                      << light << R"(], "integrator": {"type": "pathtrace", "spp": 1}})";
}

TEST(EnvMapCli, RendersAndRejectsBadImages) {
  const test::ScratchDir dir("envmap_cli");
  Image sky(16, 8);
  for (int j = 0; j < 8; ++j)
    for (int i = 0; i < 16; ++i)
      sky.pixel(i, j)[0] = sky.pixel(i, j)[1] = sky.pixel(i, j)[2] = i == 12 ? 4.0f : 1.0f;
  write_exr(dir / "sky.exr", sky);
  write_png(dir / "sky.png", sky);
  const fs::path err = dir / "err.txt";

  // A good image, relative to the scene's folder: the camera looks along +y, i.e. u = 1/4 (column 4).
  write_env_scene(dir / "good.json", R"({"type": "environment", "file": "sky.exr", "intensity": 2})");
  ASSERT_EQ(run_env("render -q " + (dir / "good.json").string() + " -o " + (dir / "good.exr").string(), err),
            0);
  const Image img = read_exr(dir / "good.exr");
  EXPECT_NEAR(img.pixel(4, 4)[0], 2.0f, 1e-6f);

  struct Case {
    std::string light, needle;
  };
  for (const Case& c :
       {Case{R"({"type": "environment", "file": "missing.exr"})", "/lights/0/file"},
        Case{R"({"type": "environment", "file": "sky.png"})", "not an OpenEXR file"},
        Case{R"({"type": "environment", "file": "sky.exr", "radiance": 1})", "/lights/0/radiance"}}) {
    write_env_scene(dir / "bad.json", c.light);
    const fs::path out = dir / "bad.exr";
    EXPECT_EQ(run_env("render -q " + (dir / "bad.json").string() + " -o " + out.string(), err), 2) << c.light;
    EXPECT_FALSE(fs::exists(out)) << c.light;
    std::ifstream in(err);
    const std::string msg((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_NE(msg.find("bad.json"), std::string::npos) << msg;
    EXPECT_NE(msg.find(c.needle), std::string::npos) << msg;
  }
}

}  // namespace
}  // namespace nimbus
