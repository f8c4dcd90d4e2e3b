// The scene's `transform` block (io/transform_json.h).
#include "io/transform_json.h"

#include <fmt/format.h>

#include <cmath>

#include "nimbus/error.h"

namespace nimbus {

namespace {

[[noreturn]] void fail_at(const JsonObject& o, const std::string& path, const std::string& message) {
  throw Error(fmt::format("{}: {}: {}", o.where(), path, message));
}

// `scale`: one number (uniform) or three, none zero (a negative one mirrors).
Vec3 parse_scale(JsonObject& o) {
  Vec3 s;
  if (o.raw("scale").is_number()) {
    s = Vec3(o.number("scale", -1e300, 1e300));
    if (s.x == 0.0) o.fail("scale", "must not be zero");
  } else if (o.raw("scale").is_array()) {
    s = o.vec3("scale");
    for (int a = 0; a < 3; ++a)
      if (s[a] == 0.0) fail_at(o, fmt::format("{}/{}", o.path_of("scale"), a), "must not be zero");
  } else {
    o.fail("scale", "must be a number or an array [sx, sy, sz]");
  }
  return s;
}

Transform parse_rotation(JsonObject r) {
  const Vec3 axis = r.vec3("axis");
  const double len = length(axis);
  if (!(len > 0.0)) r.fail("axis", "must have non-zero length");
  if (!std::isfinite(len)) r.fail("axis", "must have a finite length");
  const double degrees = r.number("degrees", -1e300, 1e300);
  r.finish();
  return Transform::rotation(axis, degrees);
}

double det3(const Transform::Matrix34& m) {
  return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
         m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
         m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

// `matrix`: 4 rows of 4 finite numbers, the last 0 0 0 1.
Transform::Matrix34 parse_matrix(JsonObject& o) {
  const nlohmann::json& v = o.raw("matrix");
  const std::string path = o.path_of("matrix");
  if (!v.is_array() || v.size() != 4) o.fail("matrix", "must be an array of 4 rows of 4 numbers");
  double m[4][4];
  for (int i = 0; i < 4; ++i) {
    const std::string row = fmt::format("{}/{}", path, i);
    if (!v[i].is_array() || v[i].size() != 4) fail_at(o, row, "must be an array of 4 numbers");
    for (int j = 0; j < 4; ++j) {
      const nlohmann::json& x = v[i][j];
      if (!x.is_number()) fail_at(o, fmt::format("{}/{}", row, j), "must be a number");
      m[i][j] = x.get<double>();
      if (!std::isfinite(m[i][j])) fail_at(o, fmt::format("{}/{}", row, j), "must be finite");
    }
  }
  if (!(m[3][0] == 0.0 && m[3][1] == 0.0 && m[3][2] == 0.0 && m[3][3] == 1.0))
    fail_at(o, path + "/3", "must be [0, 0, 0, 1] (an affine map)");
  Transform::Matrix34 r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 4; ++j) r[i][j] = m[i][j];
  return r;
}

}  // namespace

Transform parse_transform(JsonObject o) {
  Transform::Matrix34 m;
  std::string field;  // where a singular result is reported
  if (o.present("matrix")) {
    for (const char* other : {"scale", "rotate", "translate"})
      if (o.has(other)) o.fail(other, "cannot be combined with \"matrix\" (use one form or the other)");
    m = parse_matrix(o);
    field = o.path_of("matrix");
  } else {
    // Scale, then the rotations in order, then the translation.
    Transform t;
    if (o.present("scale")) {
      const Vec3 s = parse_scale(o);
      try {
        t = Transform::scaling(s);
      } catch (const Error&) {  // a product of the components under- or overflows
        o.fail("scale", "must give an invertible transform (components too small or too large)");
      }
    }
    if (o.present("rotate"))
      for (JsonObject& r : o.array_of_objects("rotate", true)) t = t.then(parse_rotation(r));
    t = t.then(Transform::translation(o.vec3("translate", Vec3(0.0))));
    m = t.matrix();
    field = o.path();
  }
  o.finish();
  if (!Transform::is_invertible(m))
    fail_at(o, field, fmt::format("must be finite and invertible (determinant {:g})", det3(m)));
  return Transform::from_matrix(m);
}

Transform parse_optional_transform(JsonObject& parent, const std::string& key) {
  return parent.present(key) ? parse_transform(parent.object(key)) : Transform();
}

}  // namespace nimbus
