// nimbus render end to end: outputs and their headers, failed runs leave existing files alone, and
// SIGINT writes a flagged partial image under its own name; --resume and --time.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <thread>

#include "nimbus/image.h"
#include "support/cli.h"
#include "support/scratch_dir.h"

namespace nimbus {
namespace {

namespace fs = std::filesystem;
using test::meta_value;

void write_render_scene(const fs::path& file, int size, int spp) {
  std::ofstream(file) << R"({"camera": {"position": [0, -4, 0], "look_at": [0, 0, 0], "up": [0, 0, 1],
    "fov_y_deg": 30, "width": )"
                      << size << R"(, "height": )" << size << R"(},
    "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": 5.0,
               "phase": {"type": "hg", "g": 0.7}}],
    "lights": [{"type": "directional", "direction": [1, 1, -1], "irradiance": 2.0},
               {"type": "environment", "radiance": 0.1}],
    "integrator": {"type": "pathtrace", "spp": )"
                      << spp << "}}";
}

int run_render(const std::string& args) {
  const int status = std::system((std::string(NIMBUS_CLI) + " " + args).c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(RenderCli, WritesExrWithHeaderAndPreview) {
  const test::ScratchDir scratch("render_cli_ok");
  const fs::path& dir = scratch.path;
  write_render_scene(dir / "s.json", 16, 2);
  ASSERT_EQ(run_render("render " + (dir / "s.json").string() + " -o " + (dir / "a.exr").string() +
                       " --preview " + (dir / "a.png").string() + " --quiet --seed 3"),
            0);
  ImageMetadata meta;
  const Image img = read_exr(dir / "a.exr", &meta);
  EXPECT_EQ(img.width, 16);
  EXPECT_EQ(meta_value(meta, "nimbus/partial"), "false");
  EXPECT_EQ(meta_value(meta, "nimbus/seed"), "3");
  EXPECT_EQ(meta_value(meta, "nimbus/integrator"), "pathtrace");
  EXPECT_NE(meta_value(meta, "nimbus/scene").find("\"sigma_s\":5.0"), std::string::npos);
  EXPECT_TRUE(fs::exists(dir / "a.png"));
}

TEST(RenderCli, FailedRunKeepsTheExistingOutput) {
  const test::ScratchDir scratch("render_cli_keep");
  const fs::path& dir = scratch.path;
  write_render_scene(dir / "s.json", 8, 1);
  std::ofstream(dir / "out.exr") << "precious";
  EXPECT_EQ(run_render("render " + (dir / "s.json").string() + " -o " + (dir / "out.exr").string() +
                       " --integrator nope --quiet 2>/dev/null"),
            2);
  EXPECT_EQ(run_render("render " + (dir / "s.json").string() + " -o " + (dir / "out.tif").string() +
                       " --quiet 2>/dev/null"),
            2);
  EXPECT_EQ(run_render("render " + (dir / "s.json").string() + " -o " + (dir / "nodir" / "x.exr").string() +
                       " --quiet 2>/dev/null"),
            2);
  std::ifstream in(dir / "out.exr");
  std::string content;
  in >> content;
  EXPECT_EQ(content, "precious");
  int files = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++files;
  EXPECT_EQ(files, 2);  // s.json and out.exr: no temporaries, no new outputs
}

TEST(RenderCli, SigintWritesAFlaggedPartialImage) {
  const test::ScratchDir scratch("render_cli_sigint");
  const fs::path& dir = scratch.path;
  write_render_scene(dir / "s.json", 32, 1 << 20);  // hours of work: it will be interrupted
  std::ofstream(dir / "out.exr") << "precious";
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    execl(NIMBUS_CLI, NIMBUS_CLI, "render", (dir / "s.json").c_str(), "-o", (dir / "out.exr").c_str(),
          "--quiet", "--threads", "1", static_cast<char*>(nullptr));
    _exit(127);
  }
  // Long enough for the first pass (1 spp of 32 x 32) on a loaded machine.
  std::this_thread::sleep_for(std::chrono::milliseconds(2000));
  kill(pid, SIGINT);
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 1);
  ImageMetadata meta;
  const Image partial = read_exr(dir / "out.partial.exr", &meta);
  EXPECT_EQ(meta_value(meta, "nimbus/partial"), "true");
  EXPECT_EQ(partial.width, 32);
  // A whole image at the spp of the last whole pass (a power of two), not a black part.
  const int spp = std::stoi(meta_value(meta, "nimbus/spp"));
  EXPECT_GE(spp, 1);
  EXPECT_EQ(spp & (spp - 1), 0);
  EXPECT_EQ(read_exr_state(dir / "out.partial.exr").spp, spp);
  int black = 0;  // the environment lights every pixel of a whole pass
  for (int y = 0; y < partial.height; ++y)
    for (int x = 0; x < partial.width; ++x) black += partial.pixel(x, y)[2] == 0.0f;
  EXPECT_EQ(black, 0);
  std::ifstream in(dir / "out.exr");
  std::string content;
  in >> content;
  EXPECT_EQ(content, "precious");
}

TEST(RenderCli, ResumeEqualsOneRenderBitForBit) {
  const test::ScratchDir scratch("render_cli_resume");
  const fs::path& dir = scratch.path;
  write_render_scene(dir / "s.json", 12, 6);
  const std::string s = (dir / "s.json").string() + " --quiet --layers depth,direct ";
  ASSERT_EQ(run_render("render " + s + "-o " + (dir / "one.exr").string()), 0);
  ASSERT_EQ(run_render("render " + s + "-o " + (dir / "two.exr").string() + " --spp 3 --threads 1"), 0);
  // Continued in place, on two threads, to 6 spp.
  ASSERT_EQ(run_render("render --quiet --resume " + (dir / "two.exr").string() + " --threads 2 --spp 6"), 0);
  ImageMetadata meta;
  const Image one = read_exr(dir / "one.exr"), two = read_exr(dir / "two.exr", &meta);
  EXPECT_EQ(meta_value(meta, "nimbus/spp"), "6");
  ASSERT_EQ(one.rgb.size(), two.rgb.size());
  EXPECT_EQ(0, std::memcmp(one.rgb.data(), two.rgb.data(), one.rgb.size() * sizeof(float)));
  EXPECT_EQ(0, std::memcmp(one.alpha.data(), two.alpha.data(), one.alpha.size() * sizeof(float)));
  const FilmState a = read_exr_state(dir / "one.exr"), b = read_exr_state(dir / "two.exr");
  ASSERT_EQ(a.layers.size(), b.layers.size());
  for (size_t l = 0; l < a.layers.size(); ++l)
    EXPECT_EQ(a.layers[l].sums, b.layers[l].sums) << a.layers[l].name;
  // Nothing to add, a scene beside --resume, or a file without a state: exit 2, the file untouched.
  const auto before = fs::last_write_time(dir / "two.exr");
  EXPECT_EQ(run_render("render --quiet --resume " + (dir / "two.exr").string() + " 2>/dev/null"), 2);
  EXPECT_EQ(run_render("render " + s + "--resume " + (dir / "two.exr").string() + " --spp 9 2>/dev/null"), 2);
  EXPECT_EQ(fs::last_write_time(dir / "two.exr"), before);
  write_exr(dir / "plain.exr", one);
  EXPECT_EQ(run_render("render --quiet --resume " + (dir / "plain.exr").string() + " --spp 9 -o " +
                       (dir / "x.exr").string() + " 2>/dev/null"),
            2);
  EXPECT_FALSE(fs::exists(dir / "x.exr"));
}

TEST(RenderCli, TimeLimitGivesAWholeImageAtFewerSamples) {
  const test::ScratchDir scratch("render_cli_time");
  const fs::path& dir = scratch.path;
  write_render_scene(dir / "s.json", 16, 1 << 20);
  ASSERT_EQ(run_render("render " + (dir / "s.json").string() + " -o " + (dir / "t.exr").string() +
                       " --quiet --time 0.5 --threads 1 2>/dev/null"),
            0);
  ImageMetadata meta;
  read_exr(dir / "t.exr", &meta);
  EXPECT_EQ(meta_value(meta, "nimbus/time_limited"), "true");
  EXPECT_EQ(meta_value(meta, "nimbus/partial"), "false");
  const int spp = std::stoi(meta_value(meta, "nimbus/spp"));
  EXPECT_GE(spp, 1);
  EXPECT_LT(spp, 1 << 20);
}

TEST(RenderCli, ConvertWritesAPngAndRejectsBadInput) {
  const test::ScratchDir scratch("render_cli_convert");
  const fs::path& dir = scratch.path;
  write_render_scene(dir / "s.json", 8, 1);
  ASSERT_EQ(
      run_render("render " + (dir / "s.json").string() + " -o " + (dir / "a.exr").string() + " --quiet"), 0);
  ASSERT_EQ(
      run_render("convert " + (dir / "a.exr").string() + " " + (dir / "a.png").string() + " --exposure 1"),
      0);
  EXPECT_GT(fs::file_size(dir / "a.png"), 0u);
  std::ofstream(dir / "bad.exr") << "not an exr";
  EXPECT_EQ(
      run_render("convert " + (dir / "bad.exr").string() + " " + (dir / "b.png").string() + " 2>/dev/null"),
      2);
  EXPECT_FALSE(fs::exists(dir / "b.png"));
  EXPECT_EQ(run_render("render " + (dir / "s.json").string() + " -o " + (dir / "c.exr").string() +
                       " --integrator mfs --quiet"),
            0);
}

// --integrator switches before --set applies, so the switched-to integrator's own fields can be set;
// the scene's spp stays; a field the integrator does not know is still refused, naming it.
TEST(RenderCli, SetActsOnTheIntegratorThatIntegratorNames) {
  const test::ScratchDir scratch("render_cli_switch");
  const fs::path& dir = scratch.path;
  write_render_scene(dir / "s.json", 8, 1);
  const std::string scene = "render " + (dir / "s.json").string();
  ASSERT_EQ(run_render(scene + " -o " + (dir / "m.exr").string() +
                       " --integrator mfs --set integrator.scatter_grid_resolution=8"
                       " --set integrator.photons=2000 --quiet"),
            0);
  ImageMetadata meta;
  read_exr(dir / "m.exr", &meta);
  EXPECT_EQ(meta_value(meta, "nimbus/integrator"), "mfs");
  EXPECT_EQ(meta_value(meta, "nimbus/spp"), "1");
  const auto settings = nlohmann::json::parse(meta_value(meta, "nimbus/integrator_settings"));
  EXPECT_EQ(settings.at("scatter_grid_resolution"), 8);
  EXPECT_EQ(settings.at("photons"), 2000);
  // pathtrace has no scatter grid: refused with the field named, nothing written.
  const std::string err = (dir / "err.txt").string();
  EXPECT_EQ(run_render(scene + " -o " + (dir / "p.exr").string() +
                       " --integrator pathtrace --set integrator.scatter_grid_resolution=8 --quiet 2>" + err),
            2);
  EXPECT_FALSE(fs::exists(dir / "p.exr"));
  std::ifstream in(err);
  const std::string message((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(message.find("scatter_grid_resolution"), std::string::npos) << message;
  // Without --integrator the field is checked against the scene's integrator (pathtrace), as before.
  EXPECT_EQ(run_render(scene + " -o " + (dir / "q.exr").string() +
                       " --set integrator.scatter_grid_resolution=8 --quiet 2>/dev/null"),
            2);
}

}  // namespace
}  // namespace nimbus
