// Helpers for the volume file tests: the shared test volumes, a scratch directory, file bytes.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "io/vdb.h"
#include "nimbus/error.h"
#include "support/scratch_dir.h"

namespace nimbus::test {

inline std::filesystem::path shared_volume(const char* name) {
  return std::filesystem::path(NIMBUS_SHARED_DIR) / "data" / "volumes" / name;
}
inline const char* kCloud = "wdas_cloud_sixteenth.vdb";
inline const char* kSmoke = "openvdb_fvdb_smoke-blosc.nvdb";

inline std::vector<char> read_bytes(const std::filesystem::path& file) {
  std::ifstream is(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(is), std::istreambuf_iterator<char>()};
}

inline void write_bytes(const std::filesystem::path& file, const std::vector<char>& bytes,
                        size_t n = size_t(-1)) {
  std::ofstream os(file, std::ios::binary | std::ios::trunc);
  os.write(bytes.data(), static_cast<std::streamsize>(std::min(n, bytes.size())));
}

// Loads `file` expecting a nimbus::Error; returns its message.
inline std::string load_error(const std::filesystem::path& file, const std::string& grid = "") {
  try {
    load_density_grid(file, grid);
  } catch (const Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "no error loading " << file;
  return "";
}

}  // namespace nimbus::test

// Skips the test when the shared data directory is missing (a bare checkout).
#define NIMBUS_REQUIRE_FILE(path) \
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "missing test data " << (path)
