// Output paths, checked before any work is done, and the CSV writer (commands.h).
#include <fmt/format.h>

#include <cstdio>
#include <filesystem>

#include "commands.h"
#include "io/atomic_file.h"
#include "nimbus/error.h"

namespace nimbus::cli {

void check_output_path(const std::string& path, const std::string& option) {
  namespace fs = std::filesystem;
  if (path.empty()) throw Error(fmt::format("{}: empty file name", option));
  const fs::path p(path);
  std::error_code ec;
  if (fs::is_directory(p, ec) || !p.has_filename())
    throw Error(fmt::format("{}: {} names a folder, not a file", option, path));
  const fs::path dir = p.has_parent_path() ? p.parent_path() : fs::path(".");
  if (!fs::is_directory(dir, ec))
    throw Error(fmt::format("{}: {}: the folder '{}' does not exist", option, path, dir.string()));
}

bool write_text(const std::string& path, const std::string& text) {
  if (path.empty() || path == "-") {
    std::fwrite(text.data(), 1, text.size(), stdout);
    return true;
  }
  try {
    atomic_write_bytes(path, text);
  } catch (const Error&) {
    fmt::print(stderr, "nimbus: error: cannot write {}\n", path);
    return false;
  }
  return true;
}

}  // namespace nimbus::cli
