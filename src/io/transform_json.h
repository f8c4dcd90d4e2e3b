// The `transform` block of the scene JSON (docs/scene-format.md, "transform"): a placement of a medium
// (and of surfaces and lights) in the world, applied after the shape's own fields. Either
//     {"scale": s or [sx, sy, sz], "rotate": [{"axis": [x, y, z], "degrees": d}, ...], "translate": [x, y, z]}
// (each optional: scale first, then the rotations in the order written, then the translation), or
//     {"matrix": [[m00, m01, m02, m03], [m10, ...], [m20, ...], [0, 0, 0, 1]]}
// (row-major, world = M * local). The map must be finite and invertible; a zero scale component, a
// zero-length axis, a last matrix row other than 0 0 0 1, a matrix together with scale/rotate/translate
// and unknown fields are errors naming the file and the JSON path.
#pragma once

#include <string>

#include "core/json_reader.h"
#include "nimbus/transform.h"

namespace nimbus {

// Parses the transform object `o` (o.path() is the JSON path of the `transform` field itself, e.g.
// "/media/0/transform", and errors read "scene.json: /media/0/transform/rotate/1/axis: ..."). Calls
// o.finish(). Throws nimbus::Error.
//     Transform t = parse_transform(medium.object("transform"));
Transform parse_transform(JsonObject o);

// The optional field `key` of `parent`: the identity when absent, otherwise
// parse_transform(parent.object(key)).
Transform parse_optional_transform(JsonObject& parent, const std::string& key = "transform");

}  // namespace nimbus
