// The emission block of a medium (io/scene_emission.h).
#include "io/scene_emission.h"

#include <fmt/format.h>

#include "io/scene_fields.h"
#include "io/vdb.h"
#include "media/emission.h"
#include "nimbus/error.h"

namespace nimbus {

namespace {

// Loads `loader(file)` for the field `key`, errors naming the scene file, the field and the volume file.
template <typename Load>
auto load_field(JsonObject& o, const std::string& key, Load&& loader) {
  try {
    return loader();
  } catch (const Error& e) {
    throw Error(fmt::format("{}: {}: {}", o.where(), o.path_of(key), e.what()));
  }
}

}  // namespace

void parse_medium_emission(JsonObject& o, Medium& m, const std::filesystem::path& base_dir) {
  MediumEmission& e = m.emission;
  e.radiance = o.rgb("emission", 0.0, Rgb(0.0));
  e.emission_grid = o.string("emission_grid", "");
  e.temperature_grid = o.string("temperature_grid", "");
  e.color_grid = o.string("color_grid", "");
  const bool blackbody = !e.temperature_grid.empty();
  for (const char* key : {"temperature_scale", "temperature_offset", "intensity"})
    if (!blackbody && o.has(key)) o.fail(key, "needs a temperature_grid");
  e.temperature_scale = o.number("temperature_scale", 0.0, 1e30, 1.0);
  e.temperature_offset = o.number("temperature_offset", -1e30, 1e30, 0.0);
  e.intensity = o.number("intensity", 0.0, 1e30, 1.0);
  if (!e.emission_grid.empty() && !o.has("emission")) o.fail("emission_grid", "needs an emission (RGB)");
  if (e.emission_grid.empty() && e.temperature_grid.empty() && e.color_grid.empty()) return;

  const auto* v = std::get_if<VdbShape>(&m.shape);
  const char* first = !e.emission_grid.empty() ? "emission_grid"
                      : blackbody              ? "temperature_grid"
                                               : "color_grid";
  if (!v || v->file.empty())
    o.fail(first, "grids are read from a vdb shape's file; this medium's shape has none");
  const std::filesystem::path file = resolve_scene_path(base_dir, v->file);
  auto grids = std::make_shared<EmissionGrids>();
  if (!e.emission_grid.empty()) {
    grids->emission = std::make_shared<const DensityGrid>(
        load_field(o, "emission_grid", [&] { return load_density_grid(file, e.emission_grid); }));
    if (grids->emission->stats().min_value < 0.0)
      o.fail("emission_grid",
             fmt::format("{}: grid \"{}\" holds negative values (min {}): emission must be >= 0",
                         file.string(), e.emission_grid, grids->emission->stats().min_value));
  }
  if (blackbody) {
    grids->temperature = std::make_shared<const DensityGrid>(
        load_field(o, "temperature_grid", [&] { return load_density_grid(file, e.temperature_grid); }));
    // The lowest temperature the medium can reach: the grid's lowest value (or its background, 0) mapped.
    const double lo = std::min(0.0, grids->temperature->stats().min_value);
    const double t_min = e.temperature_scale * lo + e.temperature_offset;
    if (t_min < 0.0)
      o.fail(grids->temperature->stats().min_value < 0.0 ? "temperature_grid" : "temperature_offset",
             fmt::format("{}: grid \"{}\": temperatures down to {} K after scale and offset: must be >= 0",
                         file.string(), e.temperature_grid, t_min));
  }
  if (!e.color_grid.empty()) {
    auto c = load_field(o, "color_grid", [&] { return load_vec3_grid(file, e.color_grid); });
    for (int k = 0; k < 3; ++k) grids->color[k] = std::make_shared<const DensityGrid>(std::move(c[k]));
  }
  e.grids = grids;
}

}  // namespace nimbus
