// The scene: camera, media, lights and integrator settings, as read from a scene JSON file.
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

struct Medium {
  Shape shape;
  Transform transform;   // world = transform(the shape's own placement); identity by default
  Rgb sigma_s{1, 1, 1};  // 1/length
  Rgb sigma_a{0, 0, 0};  // 1/length
  Phase phase = IsotropicPhase{};
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

struct IntegratorSettings {
  std::string type = "pathtrace";
  int spp = 64;
  int max_events = 0;  // most scattering events on a path; 0 = unlimited
  uint64_t seed = 1;
  // The integrator's own fields as written (checked by the scene parser through the registry; each
  // integrator's header lists them).
  nlohmann::json options = nlohmann::json::object();
};

struct Scene {
  Camera camera;
  std::vector<Medium> media;
  std::vector<Light> lights;
  IntegratorSettings integrator;
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
