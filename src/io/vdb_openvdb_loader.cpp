// Volume files, the way to the OpenVDB side (io/vdb_internal.h says why it is a module): the five
// detail::*openvdb* functions call the table of libnimbus_openvdb.so, loaded on first use. Where the
// OpenVDB side is linked into the program (the tests, the sanitizer builds) they call
// it directly.
#include <fmt/format.h>

#include <filesystem>
#include <string>
#include <vector>

#include "io/vdb_internal.h"

#if NIMBUS_LAZY_OPENVDB
#include <dlfcn.h>

#include <cstdlib>
#include <system_error>

// Defined only where the OpenVDB side is linked in (its objects, not an archive member: a weak
// reference pulls nothing out of an archive).
extern "C" const nimbus::detail::OpenVdbModule* nimbus_openvdb_module() __attribute__((weak));
#else
extern "C" const nimbus::detail::OpenVdbModule* nimbus_openvdb_module();
#endif

namespace nimbus::detail {

namespace {

#if NIMBUS_LAZY_OPENVDB
namespace fs = std::filesystem;

constexpr const char* kModuleName = "libnimbus_openvdb.so";

// Where the module may be: $NIMBUS_OPENVDB_MODULE alone where it is set; else, in order, beside the
// running program as installed (BINDIR/../LIBDIR/nimbus, the same layout in the build tree), where
// `cmake --install` puts it with the configured prefix, and where the build made it.
std::vector<fs::path> module_candidates() {
  if (const char* env = std::getenv("NIMBUS_OPENVDB_MODULE"); env != nullptr && *env != '\0') return {env};
  std::vector<fs::path> out;
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec)
    out.push_back((exe.parent_path() / NIMBUS_OPENVDB_MODULE_FROM_BINDIR / kModuleName).lexically_normal());
  out.push_back(fs::path(NIMBUS_OPENVDB_MODULE_INSTALL_DIR) / kModuleName);
  out.push_back(fs::path(NIMBUS_OPENVDB_MODULE_BUILD_DIR) / kModuleName);
  return out;
}

struct Loaded {
  const OpenVdbModule* table = nullptr;
  std::string error;  // why table is null
};

Loaded load_module() {
  std::vector<std::string> tried;
  for (const fs::path& path : module_candidates()) {
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) {
      tried.push_back(path.string());
      continue;
    }
    // Never closed: OpenVDB's globals live until the process ends.
    void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
    if (handle == nullptr) return {nullptr, fmt::format("cannot load {}: {}", path.string(), dlerror())};
    using Entry = const OpenVdbModule* (*)();
    const auto entry = reinterpret_cast<Entry>(dlsym(handle, "nimbus_openvdb_module"));
    const OpenVdbModule* table = entry != nullptr ? entry() : nullptr;
    if (table == nullptr || table->abi != kOpenVdbModuleAbi)
      return {nullptr, fmt::format("{} is not this build's OpenVDB module (rebuild or reinstall nimbus)",
                                   path.string())};
    return {table, ""};
  }
  return {nullptr, fmt::format("nimbus's OpenVDB module {} was not found (looked for {}; set "
                               "NIMBUS_OPENVDB_MODULE to its path)",
                               kModuleName, fmt::join(tried, ", "))};
}
#endif

// The table, or a nimbus::Error naming `file` (what needs the module), what it could not do and why the
// module could not be loaded.
const OpenVdbModule& module_for(const std::filesystem::path& file,
                                const char* action = "cannot read an OpenVDB file") {
#if NIMBUS_LAZY_OPENVDB
  if (nimbus_openvdb_module != nullptr) return *nimbus_openvdb_module();
  static const Loaded loaded = load_module();
  if (loaded.table == nullptr) fail(file, fmt::format("{}: {}", action, loaded.error));
  return *loaded.table;
#else
  (void)file, (void)action;
  return *nimbus_openvdb_module();
#endif
}

}  // namespace

NanoHandle load_openvdb_float_grid(const std::filesystem::path& file, const std::string& grid_name,
                                   int upsample) {
  return module_for(file).load_float_grid(file, grid_name, upsample);
}

std::array<NanoHandle, 3> load_openvdb_vec3_grid(const std::filesystem::path& file,
                                                 const std::string& grid_name) {
  return module_for(file).load_vec3_grid(file, grid_name);
}

std::vector<GridInfo> inspect_openvdb_file(const std::filesystem::path& file) {
  return module_for(file).inspect_file(file);
}

DenseGrid openvdb_grid_from_dense(const DenseVolume& volume) {
  const OpenVdbModule& m = module_for(fmt::format("numpy volume '{}'", volume.name), "cannot make its grid");
  return m.grid_from_dense(volume);
}

void save_openvdb_grid(const std::shared_ptr<void>& grid, const std::filesystem::path& path) {
  module_for(path, "cannot write an OpenVDB file").save_grid(grid, path);
}

}  // namespace nimbus::detail
