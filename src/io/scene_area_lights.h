// Parsing the spot, sphere and rectangle lights of the scene's "lights" array (docs/scene-format.md,
// "Spot, sphere and rectangle lights"). Each reads the light's fields and its optional `transform`
// (baked into the light's world placement); `o` is finished by the caller.
#pragma once

#include "core/json_reader.h"
#include "nimbus/scene.h"

namespace nimbus {

SpotLight parse_spot_light(JsonObject& o);
SphereLight parse_sphere_light(JsonObject& o);
RectangleLight parse_rectangle_light(JsonObject& o);

}  // namespace nimbus
