// The "surfaces" array of a scene (io/scene_surfaces.h).
#include "io/scene_surfaces.h"

#include <fmt/format.h>

#include <cmath>

#include "io/mesh.h"
#include "io/scene_fields.h"
#include "io/transform_json.h"
#include "nimbus/error.h"

namespace nimbus {

namespace {

// `size`: [width, height], both > 0.
void rectangle_size(JsonObject& o, RectangleSurface* r) {
  const nlohmann::json& j = o.raw("size");
  if (!j.is_array() || j.size() != 2 || !j[0].is_number() || !j[1].is_number())
    o.fail("size", "must be [width, height]");
  const double w = j[0].get<double>(), h = j[1].get<double>();
  if (!(w > 0.0 && h > 0.0 && w <= 1e30 && h <= 1e30)) o.fail("size", "both sides must be > 0 and finite");
  r->width = w;
  r->height = h;
}

SurfaceShape parse_surface_shape(JsonObject o, const std::filesystem::path& base_dir) {
  const std::string type = o.string("type");
  SurfaceShape shape;
  if (type == "sphere") {
    SphereSurface s;
    s.center = o.vec3("center", s.center);
    s.radius = o.number_open_below("radius", 0.0, 1e30);
    shape = s;
  } else if (type == "rectangle") {
    RectangleSurface r;
    r.center = o.vec3("center", r.center);
    r.normal = normalize(nonzero_vec3(o, "normal", r.normal));
    r.up = nonzero_vec3(o, "up", r.up);
    if (length(cross(r.normal, normalize(r.up))) < 1e-6) o.fail("up", "must not be parallel to the normal");
    rectangle_size(o, &r);
    shape = r;
  } else if (type == "box") {
    BoxSurface b;
    read_box_corners(o, &b.min, &b.max);
    shape = b;
  } else if (type == "mesh") {
    MeshSurface m;
    m.file = o.string("file");
    const std::filesystem::path file = resolve_scene_path(base_dir, m.file);
    try {
      m.data = load_mesh(file, m.file);
    } catch (const Error& e) {
      o.fail("file", e.what());
    }
    shape = m;
  } else {
    o.fail("type", fmt::format("unknown surface shape '{}' (known: sphere, rectangle, box, mesh)", type));
  }
  o.finish();
  return shape;
}

Material parse_material(JsonObject o) {
  const int type = o.choice("type", {"diffuse", "holdout"}, -1);
  Material material;
  if (type == 0) {
    DiffuseMaterial d;
    d.albedo = o.rgb("albedo", 0.0, d.albedo);
    if (max_component(d.albedo) > 1.0)
      o.fail("albedo", "must be <= 1 (a diffuse surface reflects at most all light)");
    material = d;
  } else if (type == 1) {
    material = HoldoutMaterial{};
  } else {
    o.fail("type", "is required (\"diffuse\" or \"holdout\")");
  }
  o.finish();
  return material;
}

}  // namespace

Surface parse_surface(JsonObject o, const std::filesystem::path& base_dir) {
  Surface s;
  s.shape = parse_surface_shape(o.object("shape"), base_dir);
  if (o.has("material")) s.material = parse_material(o.object("material"));
  s.transform = parse_optional_transform(o);
  o.finish();
  return s;
}

}  // namespace nimbus
