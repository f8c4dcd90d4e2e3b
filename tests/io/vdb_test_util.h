// Helpers for the volume file tests: the shared test volumes, a scratch directory, file bytes.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace nimbus::test {

inline std::filesystem::path shared_volume(const char* name) {
  return std::filesystem::path(NIMBUS_SHARED_DIR) / "data" / "volumes" / name;
}
inline const char* kCloud = "wdas_cloud_sixteenth.vdb";
inline const char* kSmoke = "openvdb_fvdb_smoke-blosc.nvdb";

// A fresh directory under the system temp dir, removed when the object dies.
struct ScratchDir {
  std::filesystem::path path;
  explicit ScratchDir(const std::string& tag) {
    path = std::filesystem::temp_directory_path() /
           ("nimbus_" + tag + "_" + std::to_string(::getpid()) + "_" + std::to_string(counter()++));
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
  }
  ~ScratchDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
  std::filesystem::path operator/(const std::string& name) const { return path / name; }
  static int& counter() {
    static int n = 0;
    return n;
  }
};

inline std::vector<char> read_bytes(const std::filesystem::path& file) {
  std::ifstream is(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(is), std::istreambuf_iterator<char>()};
}

inline void write_bytes(const std::filesystem::path& file, const std::vector<char>& bytes,
                        size_t n = size_t(-1)) {
  std::ofstream os(file, std::ios::binary | std::ios::trunc);
  os.write(bytes.data(), static_cast<std::streamsize>(std::min(n, bytes.size())));
}

}  // namespace nimbus::test

// Skips the test when the shared data directory is missing (a bare checkout).
#define NIMBUS_REQUIRE_FILE(path) \
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "missing test data " << (path)
