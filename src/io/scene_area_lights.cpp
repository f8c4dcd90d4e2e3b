// The spot, sphere and rectangle lights of the scene (io/scene_area_lights.h).
#include "io/scene_area_lights.h"

#include <cmath>

#include "io/scene_fields.h"
#include "io/transform_json.h"

namespace nimbus {

namespace {

// Whether the transform's 3x3 part is a rotation (or reflection) times one uniform scale, and that
// scale: the area lights keep their shape (a sphere stays a sphere, a rectangle a rectangle).
bool similarity_scale(const Transform& t, double* scale) {
  const Vec3 cx = t.vector({1, 0, 0}), cy = t.vector({0, 1, 0}), cz = t.vector({0, 0, 1});
  const double s = length(cx);
  const double tol = 1e-9 * s * s;
  *scale = s;
  return std::abs(dot(cy, cy) - s * s) <= tol && std::abs(dot(cz, cz) - s * s) <= tol &&
         std::abs(dot(cx, cy)) <= tol && std::abs(dot(cy, cz)) <= tol && std::abs(dot(cx, cz)) <= tol;
}

// The transform of an area light: identity when absent; must keep shapes (see similarity_scale).
Transform area_transform(JsonObject& o, double* scale) {
  const Transform t = parse_optional_transform(o);
  if (!similarity_scale(t, scale))
    o.fail("transform", "must be rotations, one uniform scale and a translation for an area light");
  return t;
}

// `radiance` or `power` (exactly one); power (W) becomes radiance through power_per_radiance (W per
// unit radiance: the emitting area times pi, the cosine-weighted solid angle of one side).
Rgb radiance_or_power(JsonObject& o, double power_per_radiance) {
  const bool has_radiance = o.present("radiance"), has_power = o.present("power");
  if (has_radiance && has_power) o.fail("power", "give either radiance or power, not both");
  if (has_radiance) return o.rgb("radiance", 0.0);
  if (!has_power) o.fail_here("an area light needs \"radiance\" or \"power\"");
  return o.rgb("power", 0.0) / power_per_radiance;
}

}  // namespace

SpotLight parse_spot_light(JsonObject& o) {
  SpotLight s;
  s.position = o.vec3("position");
  s.direction = unit_direction(o, "direction");
  s.intensity = o.rgb("intensity", 0.0);
  s.cone_angle_deg = o.number_open_below("cone_angle_deg", 0.0, 180.0);
  s.blend = o.number("blend", 0.0, 1.0, s.blend);
  const Transform t = parse_optional_transform(o);
  s.position = t.point(s.position);
  s.direction = normalize(t.vector(s.direction));
  return s;
}

SphereLight parse_sphere_light(JsonObject& o) {
  SphereLight s;
  s.center = o.vec3("center");
  s.radius = o.number_open_below("radius", 0.0, 1e30);
  s.visible = o.boolean("visible", s.visible);
  double scale = 1.0;
  const Transform t = area_transform(o, &scale);
  s.center = t.point(s.center);
  s.radius *= scale;
  // Power = radiance x area x pi: 4 pi^2 r^2 L (each surface point emits pi L per unit area).
  s.radiance = radiance_or_power(o, 4.0 * kPi * kPi * s.radius * s.radius);
  return s;
}

RectangleLight parse_rectangle_light(JsonObject& o) {
  RectangleLight r;
  r.center = o.vec3("center");
  r.normal = normalize(nonzero_vec3(o, "normal", r.normal));
  const Vec3 up = normalize(nonzero_vec3(o, "up", r.up));
  if (length(cross(r.normal, up)) < 1e-6) o.fail("up", "must not be parallel to the normal");
  const nlohmann::json& j = o.raw("size");
  if (!j.is_array() || j.size() != 2 || !j[0].is_number() || !j[1].is_number())
    o.fail("size", "must be [width, height]");
  r.width = j[0].get<double>();
  r.height = j[1].get<double>();
  if (!(r.width > 0.0 && r.height > 0.0 && r.width <= 1e30 && r.height <= 1e30))
    o.fail("size", "both sides must be > 0 and finite");
  r.visible = o.boolean("visible", r.visible);
  double scale = 1.0;
  const Transform t = area_transform(o, &scale);
  r.center = t.point(r.center);
  // `up` made perpendicular to the normal; a similarity maps normals like vectors (up to scale).
  r.up = normalize(t.vector(up - r.normal * dot(up, r.normal)));
  r.normal = normalize(t.vector(r.normal));
  r.width *= scale;
  r.height *= scale;
  // Power = radiance x area x pi (one side, Lambertian).
  r.radiance = radiance_or_power(o, kPi * r.width * r.height);
  return r;
}

}  // namespace nimbus
