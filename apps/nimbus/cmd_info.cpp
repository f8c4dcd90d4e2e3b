// nimbus info FILE: lists the grids of a .vdb or .nvdb file (name, type, class, active voxels, tiles,
// index and world bboxes, voxel size, value range). Bad input: `nimbus: error: FILE: message`, exit 2.
#include <fmt/format.h>

#include <filesystem>
#include <string>

#include "commands.h"
#include "io/vdb.h"
#include "nimbus/image.h"

namespace nimbus::cli {

namespace {

// An EXR: its size, window and string attributes (a nimbus render's header: nimbus/spp, nimbus/partial...).
int run_exr_info(const std::string& path) {
  ImageMetadata meta;
  const Image img = read_exr(path, &meta);
  fmt::print("{}: {}x{} pixels", path, img.width, img.height);
  if (img.display_width != 0)
    fmt::print(" at ({}, {}) of {}x{}", img.origin_x, img.origin_y, img.display_width, img.display_height);
  fmt::print("\n");
  for (const auto& [k, v] : meta) fmt::print("{} {}\n", k, v);
  return kExitOk;
}

int run_info(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".exr") return run_exr_info(path);
  const std::vector<GridInfo> grids = inspect_volume_file(path);
  fmt::print("{}: {} grid{}\n", path, grids.size(), grids.size() == 1 ? "" : "s");
  for (size_t i = 0; i < grids.size(); ++i) {
    const GridInfo& g = grids[i];
    fmt::print("grid {}: {}\n", i, g.name.empty() ? "(unnamed)" : g.name);
    fmt::print("  type          {}\n", g.type);
    fmt::print("  class         {}\n", g.grid_class);
    fmt::print("  active voxels {}\n", g.active_voxels);
    fmt::print("  active tiles  {}\n", g.tiles);
    if (g.empty) {
      fmt::print("  index bbox    (empty)\n");
    } else {
      fmt::print("  index bbox    [{}, {}, {}] .. [{}, {}, {}]  ({} x {} x {})\n", g.index_min[0],
                 g.index_min[1], g.index_min[2], g.index_max[0], g.index_max[1], g.index_max[2],
                 int64_t(g.index_max[0]) - g.index_min[0] + 1, int64_t(g.index_max[1]) - g.index_min[1] + 1,
                 int64_t(g.index_max[2]) - g.index_min[2] + 1);
      fmt::print("  world bbox    ({:.6g}, {:.6g}, {:.6g}) .. ({:.6g}, {:.6g}, {:.6g})\n",
                 g.world_bounds.lo.x, g.world_bounds.lo.y, g.world_bounds.lo.z, g.world_bounds.hi.x,
                 g.world_bounds.hi.y, g.world_bounds.hi.z);
    }
    fmt::print("  voxel size    {:.6g} x {:.6g} x {:.6g}\n", g.voxel_size.x, g.voxel_size.y, g.voxel_size.z);
    if (g.has_value_range)
      fmt::print("  values        min {:.6g}  max {:.6g}  mean (active) {:.6g}\n", g.min_value, g.max_value,
                 g.mean_active);
    else
      fmt::print("  values        (n/a for this type)\n");
  }
  return kExitOk;
}

}  // namespace

void add_info_command(CLI::App& app, Action& action) {
  auto* cmd =
      app.add_subcommand("info", "List the grids of a volume file (.vdb or .nvdb), or an EXR's header");
  auto path = std::make_shared<std::string>();
  cmd->add_option(
         "file", *path,
         "OpenVDB (.vdb) or NanoVDB (.nvdb) file, or an EXR (its size and header attributes, one per line)")
      ->required();
  cmd->footer(
      "The world bbox is the active index bbox (voxel centres) through the grid's transform.\n"
      "Exit status 2 on a missing, unreadable or corrupt file.");
  cmd->callback([&action, path] { action = [path] { return run_info(*path); }; });
}

}  // namespace nimbus::cli
