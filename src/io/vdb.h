// TEMPORARY STUB (replaced by the vdb branch): the DensityGrid interface the renderer codes against.
#pragma once
#include <filesystem>
#include <string>
#include "core/math.h"
namespace nimbus {
class DensityGrid {
 public:
  static DensityGrid load(const std::filesystem::path& file, const std::string& grid_name = "");
  Vec3 world_to_index(const Vec3& p) const { return p; }
  Vec3 index_to_world(const Vec3& p) const { return p; }
  double density_index(const Vec3&) const { return 0.0; }
  double max_density_index(const Vec3&, const Vec3&) const { return 0.0; }
  Vec3 index_lo() const { return Vec3(0.0); }
  Vec3 index_hi() const { return Vec3(0.0); }
};
}  // namespace nimbus
