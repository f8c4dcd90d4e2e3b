// The scene: camera, media, surfaces, lights and integrator settings, as read from a scene JSON file.
// docs/scene-format.md documents every field; src/io/scene_json.cpp parses and validates it.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <variant>
#include <vector>

#include "nimbus/phase.h"
#include "nimbus/transform.h"
#include "nimbus/types.h"

namespace nimbus {

class DensityGrid;
class TriangleMesh;
struct EmissionGrids;

// Pinhole camera. fov_y_deg is the full vertical field of view; image row 0 is the top;
// camera right = forward x up.
struct Camera {
  Vec3 position{0, -5, 0};
  Vec3 look_at{0, 0, 0};
  Vec3 up{0, 0, 1};
  double fov_y_deg = 40.0;
  int width = 256, height = 256;
};

struct SphereShape {
  Vec3 center{0, 0, 0};
  double radius = 1.0;
};
struct BoxShape {
  Vec3 min{-1, -1, -1}, max{1, 1, 1};
};
// A density grid from an OpenVDB/NanoVDB file: the file's own index-to-world transform, then
// `scale`, then `translate` (then the medium's transform). The grid value multiplies sigma_s and sigma_a.
struct VdbShape {
  std::string file;  // as written in the scene
  std::string grid;  // empty: the first float grid
  Vec3 translate{0, 0, 0};
  double scale = 1.0;
  std::shared_ptr<const DensityGrid> data;  // loaded by load_scene
};
// A procedural cumulus-like cloud (noise-displaced union of blobs), voxelised once into a grid.
struct CloudShape {
  Vec3 center{0, 0, 0};
  double radius = 1.0;  // overall size
  uint32_t seed = 1;
  int resolution = 128;                     // voxels along the longest axis
  std::shared_ptr<const DensityGrid> data;  // built by load_scene
};
using Shape = std::variant<SphereShape, BoxShape, VdbShape, CloudShape>;

// A medium's emission and its further grids (docs/scene-format.md, "Emission"; media/emission.h). The
// emitted radiance per unit length is radiance x (the emission grid, or else the shape's density) plus,
// with a temperature grid, intensity x sigma_a x the black-body RGB of scale x grid + offset (kelvin).
struct MediumEmission {
  Rgb radiance{0.0};                                        // `emission`, >= 0
  std::string emission_grid, temperature_grid, color_grid;  // grids of the vdb shape's file ("": none)
  double temperature_scale = 1.0, temperature_offset = 0.0, intensity = 1.0;
  std::shared_ptr<const EmissionGrids> grids;  // loaded by load_scene
};

struct Medium {
  Shape shape;
  Transform transform;   // world = transform(the shape's own placement); identity by default
  Rgb sigma_s{1, 1, 1};  // 1/length
  Rgb sigma_a{0, 0, 0};  // 1/length
  Phase phase = IsotropicPhase{};
  MediumEmission emission;  // none by default
};

// `direction` is the way the light travels; `irradiance` on a surface facing it. A non-zero
// angular diameter makes it a disc of uniform radiance.
struct DirectionalLight {
  Vec3 direction{0, 0, -1};
  Rgb irradiance{1, 1, 1};
  double angular_diameter_deg = 0.0;
};
struct PointLight {
  Vec3 position{0, 0, 5};
  Rgb intensity{1, 1, 1};  // W/sr
};
// Constant radiance from every direction; also what the camera sees where its ray escapes.
struct EnvironmentLight {
  Rgb radiance{1, 1, 1};
};
using Light = std::variant<DirectionalLight, PointLight, EnvironmentLight>;

// Opaque surfaces (two-sided). Shapes: an analytic sphere, a rectangle (a quad of `size` across the
// `up` direction's perpendicular and along `up`, facing `normal`), a box and a triangle mesh from a file.
struct SphereSurface {
  Vec3 center{0, 0, 0};
  double radius = 1.0;
};
struct RectangleSurface {
  Vec3 center{0, 0, 0};
  Vec3 normal{0, 0, 1};
  Vec3 up{0, 1, 0};
  double width = 1.0, height = 1.0;  // `size`: along normal x up, and along up
};
struct BoxSurface {
  Vec3 min{-1, -1, -1}, max{1, 1, 1};
};
struct MeshSurface {
  std::string file;                          // as written in the scene
  std::shared_ptr<const TriangleMesh> data;  // loaded by load_scene
};
using SurfaceShape = std::variant<SphereSurface, RectangleSurface, BoxSurface, MeshSurface>;

// Lambertian reflection of `albedo`; a holdout occludes like any surface but is the compositor's matte:
// zero radiance and zero alpha where the camera sees it.
struct DiffuseMaterial {
  Rgb albedo{0.8, 0.8, 0.8};
};
struct HoldoutMaterial {};
using Material = std::variant<DiffuseMaterial, HoldoutMaterial>;

struct Surface {
  SurfaceShape shape;
  Material material = DiffuseMaterial{};
  Transform transform;  // applied after the shape's own fields: world = transform * shape
};

struct IntegratorSettings {
  std::string type = "pathtrace";
  int spp = 64;
  int max_events = 0;  // most scattering events on a path; 0 = unlimited
  uint64_t seed = 1;
  // The integrator's own fields as written (checked by the scene parser through the registry; each
  // integrator's header lists them).
  nlohmann::json options = nlohmann::json::object();
};

// The compositing layers a film can keep besides RGBA (docs/compositing.md names their EXR channels).
inline const std::vector<std::string>& film_layer_names() {
  static const std::vector<std::string> names = {"depth",  "transmittance", "direct", "indirect",
                                                 "albedo", "normal",        "samples"};
  return names;
}

// What the image holds besides the beauty: `transparent` leaves the environment out of the colour and
// the alpha (the environment is then a plate to be composited behind); `layers` names further EXR
// layers from film_layer_names(), each at most once.
struct FilmSettings {
  bool transparent = false;
  std::vector<std::string> layers;
};

struct Scene {
  Camera camera;
  std::vector<Medium> media;
  std::vector<Surface> surfaces;
  std::vector<Light> lights;
  IntegratorSettings integrator;
  FilmSettings film;
  std::filesystem::path file;  // where it was read from (empty for built-in scenes)
  nlohmann::json source;       // the JSON it was read from, for image metadata
};

// Reads, validates and loads (volumes included) a scene file. Every error is a nimbus::Error
// naming the file and the JSON path: "scene.json: /media/0/sigma_s: must be >= 0".
Scene load_scene(const std::filesystem::path& file);
// The same from an in-memory document; `name` stands for the file in messages, relative volume
// paths resolve against `base_dir`.
Scene parse_scene(const nlohmann::json& doc, const std::string& name, const std::filesystem::path& base_dir);
// The built-in demo: a procedural cloud under a sun and a blue sky.
Scene builtin_demo_scene();

// Limits on what a scene may ask for (checked by the parser, documented in docs/scene-format.md).
inline constexpr int kMaxImageSide = 16384;
inline constexpr int64_t kMaxImagePixels = int64_t(1) << 26;  // 64 Mpixel: ~1.5 GiB of float buffers
inline constexpr int kMaxSpp = 1 << 24;

}  // namespace nimbus
