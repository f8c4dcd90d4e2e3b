// Parsing the scene's "lights" array (docs/scene-format.md).
#include "io/scene_lights.h"

#include <fmt/format.h>

#include "io/scene_area_lights.h"
#include "io/scene_environment.h"
#include "io/scene_fields.h"

namespace nimbus {

Light parse_light(JsonObject o, const std::filesystem::path& base_dir) {
  const std::string type = o.string("type");
  Light light;
  if (type == "directional") {
    DirectionalLight d;
    d.direction = unit_direction(o, "direction");
    d.irradiance = o.rgb("irradiance", 0.0);
    d.angular_diameter_deg = o.number("angular_diameter_deg", 0.0, 90.0, 0.0);
    light = d;
  } else if (type == "point") {
    PointLight p;
    p.position = o.vec3("position");
    p.intensity = o.rgb("intensity", 0.0);
    light = p;
  } else if (type == "environment") {
    light = parse_environment_light(o, base_dir);  // io/scene_environment.cpp
  } else if (type == "spot") {
    light = parse_spot_light(o);
  } else if (type == "sphere") {
    light = parse_sphere_light(o);
  } else if (type == "rectangle") {
    light = parse_rectangle_light(o);
  } else {
    o.fail("type", fmt::format("unknown light '{}' (known: directional, point, environment, spot, sphere, "
                               "rectangle)",
                               type));
  }
  o.finish();
  return light;
}

}  // namespace nimbus
