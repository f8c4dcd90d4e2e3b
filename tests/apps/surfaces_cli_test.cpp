// nimbus render with surfaces: a missing or corrupt mesh exits 2 with one "nimbus: error:" line that
// names the scene, the JSON field and the mesh file, and writes nothing (nor touches an existing
// output); a good mesh renders.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include "support/scratch_dir.h"

namespace nimbus {
namespace {

namespace fs = std::filesystem;

// A small scene: a ground rectangle and a mesh surface from `mesh_file`, under a sun.
void write_mesh_scene(const fs::path& file, const std::string& mesh_file) {
  std::ofstream(file) << R"({"camera": {"position": [0, -4, 1], "look_at": [0, 0, 0], "up": [0, 0, 1],
    "fov_y_deg": 40, "width": 8, "height": 8},
    "media": [],
    "surfaces": [
      {"shape": {"type": "rectangle", "size": [10, 10]}, "material": {"type": "diffuse", "albedo": 0.5}},
      {"shape": {"type": "mesh", "file": ")"
                      << mesh_file << R"("}, "material": {"type": "diffuse", "albedo": [0.8, 0.6, 0.4]}}],
    "lights": [{"type": "directional", "direction": [1, 1, -1], "irradiance": 2.0}],
    "integrator": {"type": "pathtrace", "spp": 1}})";
}

struct RunResult {
  int status = -1;
  std::string first_line;  // of stderr
};

// nimbus render SCENE -o DIR/out.exr --preview DIR/out.png, stderr to a file outside DIR.
RunResult render(const fs::path& dir, const fs::path& err_file) {
  const std::string cmd = std::string(NIMBUS_CLI) + " render " + (dir / "scene.json").string() + " -o " +
                          (dir / "out.exr").string() + " --preview " + (dir / "out.png").string() +
                          " --quiet 2> " + err_file.string();
  const int status = std::system(cmd.c_str());
  RunResult r;
  r.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream err(err_file);
  std::getline(err, r.first_line);
  return r;
}

std::set<std::string> files_in(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    names.insert(fs::relative(e.path(), dir).string());
  return names;
}

TEST(SurfacesCli, BadMeshesExitTwoNamingFileAndFieldAndWriteNothing) {
  const test::ScratchDir scratch("surfaces_cli_bad");
  const test::ScratchDir logs("surfaces_cli_logs");
  const fs::path& dir = scratch.path;
  fs::create_directories(dir / "meshes");
  struct Case {
    std::string file, content, message;  // content empty: no file written
  };
  const std::vector<Case> cases = {
      {"meshes/missing.obj", "", "meshes/missing.obj: no such file"},
      {"meshes/empty.obj", "\n", "meshes/empty.obj: the mesh has no triangles"},
      {"meshes/nan.obj", "v 0 0 0\nv 1 0 nan\nv 0 1 0\nf 1 2 3\n",
       "meshes/nan.obj: line 2: vertex coordinate 'nan' is not finite"},
      {"meshes/huge.obj", "v 0 0 0\nv 1 0 0\nv 0 1e200 0\nf 1 2 3\n",
       "meshes/huge.obj: vertex 3 has a coordinate inf (must be finite, at most 1e+15 in size)"},
      {"meshes/flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n",
       "meshes/flat.obj: triangle 1 is degenerate (zero area)"},
      {"meshes/index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n",
       "meshes/index.obj: a face refers to vertex 9 of 3"},
      {"meshes/cube.ply", "ply\n", "meshes/cube.ply: unsupported mesh format '.ply' (supported: .obj)"},
  };
  for (const Case& c : cases) {
    if (!c.content.empty()) std::ofstream(dir / c.file) << c.content;
    write_mesh_scene(dir / "scene.json", c.file);
    const std::set<std::string> before = files_in(dir);
    const RunResult r = render(dir, logs / "err.txt");
    EXPECT_EQ(r.status, 2) << c.file;
    EXPECT_EQ(r.first_line,
              "nimbus: error: " + (dir / "scene.json").string() + ": /surfaces/1/shape/file: " + c.message);
    EXPECT_EQ(files_in(dir), before) << c.file << ": no output, no temporaries";
  }
}

TEST(SurfacesCli, BadMeshKeepsTheExistingOutput) {
  const test::ScratchDir scratch("surfaces_cli_keep");
  const test::ScratchDir logs("surfaces_cli_keep_logs");
  const fs::path& dir = scratch.path;
  write_mesh_scene(dir / "scene.json", "gone.obj");
  std::ofstream(dir / "out.exr") << "precious";
  EXPECT_EQ(render(dir, logs / "err.txt").status, 2);
  std::ifstream in(dir / "out.exr");
  std::string content;
  in >> content;
  EXPECT_EQ(content, "precious");
  EXPECT_FALSE(fs::exists(dir / "out.png"));
}

TEST(SurfacesCli, AGoodMeshRenders) {
  const test::ScratchDir scratch("surfaces_cli_ok");
  const test::ScratchDir logs("surfaces_cli_ok_logs");
  const fs::path& dir = scratch.path;
  fs::create_directories(dir / "meshes");
  std::ofstream(dir / "meshes" / "quad.obj") << "v -1 0 0\nv 1 0 0\nv 1 0 1\nv -1 0 1\nf 1 2 3 4\n";
  write_mesh_scene(dir / "scene.json", "meshes/quad.obj");
  const RunResult r = render(dir, logs / "err.txt");
  EXPECT_EQ(r.status, 0) << r.first_line;
  EXPECT_TRUE(fs::exists(dir / "out.exr"));
  EXPECT_TRUE(fs::exists(dir / "out.png"));
}

}  // namespace
}  // namespace nimbus
