// The scene's "surfaces" array (src/io/scene_surfaces.cpp): the fields of each shape and material
// with their defaults, mesh paths resolved against the scene's folder, and the exact message for
// each bad field: file, JSON path, and for a bad mesh the mesh file's own error after it.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "nimbus/error.h"
#include "nimbus/scene.h"
#include "scene/mesh.h"
#include "support/scenes.h"
#include "support/scratch_dir.h"

namespace nimbus {
namespace {

namespace fs = std::filesystem;

constexpr const char* kQuad = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";

// A valid scene with `surfaces` (JSON text of the array).
nlohmann::json scene_with(const std::string& surfaces) {
  return nlohmann::json::parse("{" + test::camera_json() + R"(, "media": [],
    "lights": [{"type": "environment", "radiance": 1.0}], "surfaces": )" +
                               surfaces + "}");
}

Scene parse_in(const std::string& surfaces, const fs::path& base_dir = ".") {
  return parse_scene(scene_with(surfaces), "scene.json", base_dir);
}

std::string surfaces_error(const std::string& surfaces, const fs::path& base_dir = ".") {
  try {
    parse_in(surfaces, base_dir);
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

// One surface with this shape (and the default material).
std::string shape_error(const std::string& shape, const fs::path& base_dir = ".") {
  return surfaces_error(R"([{"shape": )" + shape + "}]", base_dir);
}

// One unit sphere with this material.
std::string material_error(const std::string& material) {
  return surfaces_error(R"([{"shape": {"type": "sphere", "radius": 1}, "material": )" + material + "}]");
}

TEST(SceneSurfaces, NoSurfacesByDefault) {
  const Scene s = test::scene_from_json("{" + test::camera_json() + R"(, "media": [], "lights": []})");
  EXPECT_TRUE(s.surfaces.empty());
  EXPECT_TRUE(parse_in("[]").surfaces.empty());
}

TEST(SceneSurfaces, ShapesWithTheirDefaults) {
  const Scene s = parse_in(R"([
    {"shape": {"type": "sphere", "radius": 0.5}},
    {"shape": {"type": "rectangle", "size": [2, 3]}},
    {"shape": {"type": "box", "min": [-1, -2, -3], "max": [1, 2, 3]}},
    {"shape": {"type": "sphere", "center": [1, 2, 3], "radius": 2}},
    {"shape": {"type": "rectangle", "center": [0, 0, -1], "normal": [0, 0, 2], "up": [0, 3, 0], "size": [20, 10]}}])");
  ASSERT_EQ(s.surfaces.size(), 5u);
  const auto& sphere = std::get<SphereSurface>(s.surfaces[0].shape);
  EXPECT_EQ(sphere.center, Vec3(0, 0, 0));
  EXPECT_EQ(sphere.radius, 0.5);
  const auto& rect = std::get<RectangleSurface>(s.surfaces[1].shape);
  EXPECT_EQ(rect.center, Vec3(0, 0, 0));
  EXPECT_EQ(rect.normal, Vec3(0, 0, 1));
  EXPECT_EQ(rect.up, Vec3(0, 1, 0));
  EXPECT_EQ(rect.width, 2.0);
  EXPECT_EQ(rect.height, 3.0);
  const auto& box = std::get<BoxSurface>(s.surfaces[2].shape);
  EXPECT_EQ(box.min, Vec3(-1, -2, -3));
  EXPECT_EQ(box.max, Vec3(1, 2, 3));
  EXPECT_EQ(std::get<SphereSurface>(s.surfaces[3].shape).center, Vec3(1, 2, 3));
  const auto& ground = std::get<RectangleSurface>(s.surfaces[4].shape);
  EXPECT_EQ(ground.normal, Vec3(0, 0, 1));  // normalised
  EXPECT_EQ(ground.width, 20.0);
  EXPECT_EQ(ground.height, 10.0);
}

TEST(SceneSurfaces, MaterialsWithTheirDefaults) {
  const Scene s = parse_in(R"([
    {"shape": {"type": "sphere", "radius": 1}},
    {"shape": {"type": "sphere", "radius": 1}, "material": {"type": "diffuse"}},
    {"shape": {"type": "sphere", "radius": 1}, "material": {"type": "diffuse", "albedo": 0.5}},
    {"shape": {"type": "sphere", "radius": 1}, "material": {"type": "diffuse", "albedo": [0, 0.25, 1]}},
    {"shape": {"type": "sphere", "radius": 1}, "material": {"type": "holdout"}}])");
  ASSERT_EQ(s.surfaces.size(), 5u);
  EXPECT_EQ(std::get<DiffuseMaterial>(s.surfaces[0].material).albedo, Rgb(0.8, 0.8, 0.8));
  EXPECT_EQ(std::get<DiffuseMaterial>(s.surfaces[1].material).albedo, Rgb(0.8, 0.8, 0.8));
  EXPECT_EQ(std::get<DiffuseMaterial>(s.surfaces[2].material).albedo, Rgb(0.5, 0.5, 0.5));
  EXPECT_EQ(std::get<DiffuseMaterial>(s.surfaces[3].material).albedo, Rgb(0, 0.25, 1));
  EXPECT_TRUE(std::holds_alternative<HoldoutMaterial>(s.surfaces[4].material));
}

TEST(SceneSurfaces, MeshPathsResolveAgainstTheScenesFolder) {
  const test::ScratchDir dir("surfaces_paths");
  fs::create_directories(dir / "meshes");
  std::ofstream(dir / "meshes" / "quad.obj") << kQuad;
  // parse_scene: relative to base_dir, whatever the working directory.
  const Scene s = parse_in(R"([{"shape": {"type": "mesh", "file": "meshes/quad.obj"}}])", dir.path);
  const auto& mesh = std::get<MeshSurface>(s.surfaces[0].shape);
  EXPECT_EQ(mesh.file, "meshes/quad.obj");  // as written, for messages and the EXR header
  ASSERT_NE(mesh.data, nullptr);
  EXPECT_EQ(mesh.data->triangle_count(), 2u);
  EXPECT_EQ(mesh.data->vertex_count(), 4u);
  // load_scene: relative to the scene file's folder.
  const nlohmann::json doc = scene_with(R"([{"shape": {"type": "mesh", "file": "meshes/quad.obj"}}])");
  std::ofstream(dir / "scene.json") << doc.dump();
  EXPECT_EQ(std::get<MeshSurface>(load_scene(dir / "scene.json").surfaces[0].shape).data->triangle_count(),
            2u);
  // An absolute path is used as it is.
  const std::string absolute = (dir / "meshes" / "quad.obj").string();
  const Scene a = parse_in(R"([{"shape": {"type": "mesh", "file": ")" + absolute + R"("}}])", "/nonexistent");
  EXPECT_EQ(std::get<MeshSurface>(a.surfaces[0].shape).data->vertex_count(), 4u);
}

TEST(SceneSurfacesErrors, BadMeshFilesNameTheSceneThePathAndTheMesh) {
  const test::ScratchDir dir("surfaces_bad_mesh");
  const auto mesh_error = [&](const std::string& file) {
    return shape_error(R"({"type": "mesh", "file": ")" + file + R"("})", dir.path);
  };
  const std::string at = "scene.json: /surfaces/0/shape/file: ";
  EXPECT_EQ(mesh_error("cube.obj"), at + "cube.obj: no such file");
  fs::create_directories(dir / "folder.obj");
  EXPECT_EQ(mesh_error("folder.obj"), at + "folder.obj: is a directory");
  std::ofstream(dir / "cube.stl") << "solid cube\nendsolid cube\n";
  EXPECT_EQ(mesh_error("cube.stl"), at + "cube.stl: unsupported mesh format '.stl' (supported: .obj)");
  std::ofstream(dir / "empty.obj").flush();
  EXPECT_EQ(mesh_error("empty.obj"), at + "empty.obj: the mesh has no triangles");
  std::ofstream(dir / "garbage.obj", std::ios::binary)
      << std::string("\x89PNG\r\n\x1a\n\0\0\0\rIHDR\xff\xff", 18);
  EXPECT_EQ(mesh_error("garbage.obj"), at + "garbage.obj: the mesh has no triangles");
  std::ofstream(dir / "points.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  EXPECT_EQ(mesh_error("points.obj"), at + "points.obj: the mesh has no triangles");
  std::ofstream(dir / "nan.obj") << "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n";
  EXPECT_EQ(mesh_error("nan.obj"), at + "nan.obj: line 2: vertex coordinate 'nan' is not finite");
  std::ofstream(dir / "inf.obj") << "v 0 0 0\nv 1 0 0\nv 0 inf 0\nf 1 2 3\n";
  EXPECT_EQ(mesh_error("inf.obj"), at + "inf.obj: line 3: vertex coordinate 'inf' is not finite");
  std::ofstream(dir / "huge.obj") << "v 0 0 0\nv 1 0 0\nv 0 1e300 0\nf 1 2 3\n";
  EXPECT_EQ(mesh_error("huge.obj"),
            at + "huge.obj: vertex 3 has a coordinate inf (must be finite, at most 1e+15 in size)");
  std::ofstream(dir / "flat.obj") << "v 0 0 0\nv 1 1 1\nv 2 2 2\nf 1 2 3\n";
  EXPECT_EQ(mesh_error("flat.obj"), at + "flat.obj: triangle 1 is degenerate (zero area)");
  std::ofstream(dir / "repeat.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 3 3 1\n";
  EXPECT_EQ(mesh_error("repeat.obj"), at + "repeat.obj: triangle 2 is degenerate (zero area)");
  std::ofstream(dir / "index.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n";
  EXPECT_EQ(mesh_error("index.obj"), at + "index.obj: a face refers to vertex 7 of 3");
  EXPECT_EQ(shape_error(R"({"type": "mesh"})"),
            "scene.json: /surfaces/0/shape/file: required field is missing");
  EXPECT_EQ(shape_error(R"({"type": "mesh", "file": 3})"),
            "scene.json: /surfaces/0/shape/file: must be a string, not a number");
}

TEST(SceneSurfacesErrors, TheSurfacesIndexIsInThePath) {
  const test::ScratchDir dir("surfaces_index");
  std::ofstream(dir / "quad.obj") << kQuad;
  EXPECT_EQ(surfaces_error(R"([{"shape": {"type": "mesh", "file": "quad.obj"}},
                         {"shape": {"type": "mesh", "file": "sub/gone.obj"}}])",
                           dir.path),
            "scene.json: /surfaces/1/shape/file: sub/gone.obj: no such file");
}

TEST(SceneSurfacesErrors, ShapeFields) {
  const std::string at = "scene.json: /surfaces/0/shape/";
  EXPECT_EQ(shape_error(R"({"type": "cone"})"),
            at + "type: unknown surface shape 'cone' (known: sphere, rectangle, box, mesh)");
  EXPECT_EQ(shape_error(R"({"radius": 1})"), at + "type: required field is missing");
  // sphere
  EXPECT_EQ(shape_error(R"({"type": "sphere", "radius": 0})"), at + "radius: must be > 0");
  EXPECT_EQ(shape_error(R"({"type": "sphere", "radius": -1})"), at + "radius: must be > 0");
  EXPECT_EQ(shape_error(R"({"type": "sphere"})"), at + "radius: required field is missing");
  EXPECT_EQ(shape_error(R"({"type": "sphere", "radius": 1, "centre": [0, 0, 0]})")
                .rfind(at + "centre: unknown field", 0),
            0u);
  // rectangle
  EXPECT_EQ(shape_error(R"({"type": "rectangle", "size": [1, 1], "up": [0, 0, 1]})"),
            at + "up: must not be parallel to the normal");
  EXPECT_EQ(shape_error(R"({"type": "rectangle", "size": [1, 1], "normal": [0, 1, 0]})"),
            at + "up: must not be parallel to the normal");
  EXPECT_EQ(shape_error(R"({"type": "rectangle", "size": [1, 1], "up": [0, 0, -5]})"),
            at + "up: must not be parallel to the normal");
  EXPECT_EQ(shape_error(R"({"type": "rectangle", "size": [1, 1], "normal": [0, 0, 0]})"),
            at + "normal: must have non-zero length");
  EXPECT_EQ(shape_error(R"({"type": "rectangle", "size": [1, 1], "up": [0, 0, 0]})"),
            at + "up: must have non-zero length");
  EXPECT_EQ(shape_error(R"({"type": "rectangle", "size": [0, 1]})"),
            at + "size: both sides must be > 0 and finite");
  EXPECT_EQ(shape_error(R"({"type": "rectangle", "size": [1, -2]})"),
            at + "size: both sides must be > 0 and finite");
  EXPECT_EQ(shape_error(R"({"type": "rectangle", "size": [1, 1e31]})"),
            at + "size: both sides must be > 0 and finite");
  EXPECT_EQ(shape_error(R"({"type": "rectangle", "size": [1, 1, 1]})"), at + "size: must be [width, height]");
  EXPECT_EQ(shape_error(R"({"type": "rectangle", "size": 1})"), at + "size: must be [width, height]");
  EXPECT_EQ(shape_error(R"({"type": "rectangle"})"), at + "size: required field is missing");
  // box
  EXPECT_EQ(shape_error(R"({"type": "box", "min": [0, 0, 0], "max": [1, 0, 1]})"),
            at + "max: must exceed min on every axis");
  EXPECT_EQ(shape_error(R"({"type": "box", "min": [0, 0, 0], "max": [1, 1, -1]})"),
            at + "max: must exceed min on every axis");
  EXPECT_EQ(shape_error(R"({"type": "box", "max": [1, 1, 1]})"), at + "min: required field is missing");
  EXPECT_EQ(shape_error(R"({"type": "box", "min": [0, 0, 0], "max": [1, 1]})"),
            at + "max: must be an array of 3 numbers");
  // Fields of another shape are unknown here.
  EXPECT_EQ(shape_error(R"({"type": "box", "min": [0, 0, 0], "max": [1, 1, 1], "radius": 1})")
                .rfind(at + "radius: unknown field", 0),
            0u);
}

TEST(SceneSurfacesErrors, MaterialFields) {
  const std::string at = "scene.json: /surfaces/0/material/";
  EXPECT_EQ(material_error(R"({"type": "diffuse", "albedo": -0.1})"), at + "albedo: must be >= 0");
  EXPECT_EQ(material_error(R"({"type": "diffuse", "albedo": [0.5, -0.5, 0.5]})"),
            at + "albedo/1: must be >= 0");
  EXPECT_EQ(material_error(R"({"type": "diffuse", "albedo": 1.01})"),
            at + "albedo: must be <= 1 (a diffuse surface reflects at most all light)");
  EXPECT_EQ(material_error(R"({"type": "diffuse", "albedo": [0.5, 0.5, 2]})"),
            at + "albedo: must be <= 1 (a diffuse surface reflects at most all light)");
  EXPECT_EQ(material_error(R"({"type": "diffuse", "albedo": [0.5, 0.5]})"),
            at + "albedo: must be a number or an array [r, g, b]");
  EXPECT_EQ(material_error(R"({"type": "glass"})"), at + R"(type: must be "diffuse" or "holdout")");
  EXPECT_EQ(material_error(R"({"albedo": 0.5})"), at + R"(type: is required ("diffuse" or "holdout"))");
  EXPECT_EQ(material_error(R"({"type": "holdout", "albedo": 0.5})").rfind(at + "albedo: unknown field", 0),
            0u);
  EXPECT_EQ(material_error(R"({"type": "diffuse", "albedo": 0.5, "roughness": 0.1})")
                .rfind(at + "roughness: unknown field", 0),
            0u);
  // The edges are fine.
  EXPECT_EQ(material_error(R"({"type": "diffuse", "albedo": 0})"), "(no error)");
  EXPECT_EQ(material_error(R"({"type": "diffuse", "albedo": [1, 1, 1]})"), "(no error)");
}

TEST(SceneSurfacesErrors, SurfaceEntries) {
  EXPECT_EQ(surfaces_error(R"([{"shape": {"type": "sphere", "radius": 1}, "transfrom": {}}])")
                .rfind("scene.json: /surfaces/0/transfrom: unknown field", 0),
            0u);
  EXPECT_EQ(surfaces_error(R"([{"material": {"type": "holdout"}}])"),
            "scene.json: /surfaces/0/shape: required field is missing");
  EXPECT_EQ(surfaces_error(R"([3])"), "scene.json: /surfaces/0: must be an object, not a number");
  EXPECT_EQ(surfaces_error(R"({"shape": {}})"), "scene.json: /surfaces: must be an array, not an object");
}

}  // namespace
}  // namespace nimbus
