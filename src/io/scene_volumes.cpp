// The volumes of a scene (scene_volumes.h): .vdb/.nvdb shapes loaded, procedural clouds voxelised.
#include "io/scene_volumes.h"

#include <fmt/format.h>
#include <nanovdb/util/GridBuilder.h>

#include "io/scene_fields.h"
#include "io/vdb.h"
#include "media/cloud.h"
#include "nimbus/error.h"

namespace nimbus {

void load_vdb_shape(VdbShape& v, const std::filesystem::path& base_dir, const std::string& where,
                    const std::string& json_path) {
  const std::filesystem::path file = resolve_scene_path(base_dir, v.file);
  try {
    v.data = std::make_shared<const DensityGrid>(load_density_grid(file, v.grid));
  } catch (const Error& e) {
    throw Error(fmt::format("{}: {}/file: {}", where, json_path, e.what()));
  }
}

void build_cloud_shape(CloudShape& c) {
  const int n = c.resolution;
  const double h = 2.0 * c.radius / n;
  nanovdb::GridBuilder<float> builder(0.0f, nanovdb::GridClass::FogVolume);
  const uint32_t seed = c.seed;
  builder(
      [&](const nanovdb::Coord& ijk) {
        const Vec3 unit((ijk[0] + 0.5) / n * 2.0 - 1.0, (ijk[1] + 0.5) / n * 2.0 - 1.0,
                        (ijk[2] + 0.5) / n * 2.0 - 1.0);
        return float(procedural_cloud_density(unit, seed));
      },
      nanovdb::CoordBBox(nanovdb::Coord(0), nanovdb::Coord(n - 1)));
  const Vec3 origin = c.center - Vec3(c.radius) + Vec3(0.5 * h);
  auto handle = builder.getHandle<>(h, nanovdb::Vec3d(origin.x, origin.y, origin.z), "cloud");
  c.data = std::make_shared<const DensityGrid>(
      DensityGrid::from_nanovdb(std::move(handle), fmt::format("procedural cloud (seed {})", c.seed)));
}

Scene builtin_demo_scene() { return parse_scene(builtin_demo_document(), "(built-in demo)", "."); }

nlohmann::json builtin_demo_document() {
  return {{"camera",
           {{"position", {0.0, -4.2, 0.35}},
            {"look_at", {0.0, 0.0, 0.0}},
            {"up", {0, 0, 1}},
            {"fov_y_deg", 36},
            {"width", 320},
            {"height", 240}}},
          {"media",
           {{{"shape",
              {{"type", "cloud"}, {"center", {0, 0, 0}}, {"radius", 1.2}, {"seed", 7}, {"resolution", 128}}},
             {"sigma_s", 12.0},
             {"sigma_a", 0.02},
             {"phase", {{"type", "hg"}, {"g", 0.85}}}}}},
          {"lights",
           {{{"type", "directional"},
             {"direction", {-0.75, -0.3, -0.55}},
             {"irradiance", {3.4, 3.2, 2.9}},
             {"angular_diameter_deg", 0.53}},
            {{"type", "environment"}, {"radiance", {0.07, 0.12, 0.25}}}}},
          {"integrator", {{"type", "pathtrace"}, {"spp", 256}, {"seed", 1}}}};
}

}  // namespace nimbus
