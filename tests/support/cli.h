// Running the nimbus program from tests (NIMBUS_CLI, set by CMake) and reading what it wrote.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "nimbus/image.h"

namespace nimbus::test {

struct CliRun {
  int rc = -1;
  std::string out;  // stdout and stderr together
};

// `ENV nimbus ARGS` with its output captured; ENV: shell variable assignments, each followed by a space.
inline CliRun run_cli_env(const std::string& env, const std::string& args) {
  CliRun r;
  const std::string cmd = env + std::string(NIMBUS_CLI) + " " + args + " 2>&1";
  FILE* p = ::popen(cmd.c_str(), "r");
  if (!p) return r;
  char buf[4096];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) r.out.append(buf, n);
  const int status = ::pclose(p);
  r.rc = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

// `nimbus ARGS` with its output captured.
inline CliRun run_cli(const std::string& args) { return run_cli_env("", args); }

// `nimbus ARGS` with its output left in the test log; the exit code.
inline int run_cli_status(const std::string& args) {
  const int status = std::system((std::string(NIMBUS_CLI) + " " + args).c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// A scene of one .vdb or .nvdb volume `volume` (sigma_s 4, framed for fuzz/data/tiny.vdb) under a
// directional light, then `extra_lights` (JSON objects, each preceded by a comma).
inline void write_vdb_scene(const std::filesystem::path& file, const std::string& volume, int width,
                            int height, const std::string& integrator, const std::string& extra_lights = "") {
  std::ofstream(file) << R"({"camera": {"position": [0.25, -5, -0.25], "look_at": [0.25, 0, -0.25],
    "up": [0, 0, 1], "fov_y_deg": 35, "width": )"
                      << width << R"(, "height": )" << height << R"(},
    "media": [{"shape": {"type": "vdb", "file": ")"
                      << volume << R"("}, "sigma_s": 4.0}],
    "lights": [{"type": "directional", "direction": [1, 1, -1], "irradiance": 2.0})"
                      << extra_lights << R"(],
    "integrator": )" << integrator
                      << "}";
}

inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// An EXR header attribute, "(missing)" when absent.
inline std::string meta_value(const ImageMetadata& meta, const std::string& key) {
  for (const auto& [k, v] : meta)
    if (k == key) return v;
  return "(missing)";
}

// A directory for a test file's outputs, one per process (kept: the CLI tests look at it after a failure).
inline std::filesystem::path cli_temp_dir(const std::string& tag) {
  auto d = std::filesystem::temp_directory_path() / ("nimbus_" + tag + "_" + std::to_string(::getpid()));
  std::filesystem::create_directories(d);
  return d;
}

// The comma-separated fields of a CSV line (no quoting: the transport commands write none).
inline std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string> v;
  std::stringstream ss(line);
  std::string item;
  while (std::getline(ss, item, ',')) v.push_back(item);
  return v;
}

}  // namespace nimbus::test
