// The scene: camera, media, surfaces, lights and integrator settings, as read from a scene JSON file.
// docs/scene-format.md documents every field; src/io/scene_json.cpp parses and validates it.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "nimbus/phase.h"
#include "nimbus/transform.h"
#include "nimbus/types.h"

namespace nimbus {

class DensityGrid;
class EnvMap;
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
// Constant radiance from every direction, or (`file`) a lat-long HDR image around the scene
// (src/scene/env_map.h: Blender's orientation, `transform` rotations, times `intensity`); also what the
// camera sees where its ray escapes.
struct EnvironmentLight {
  Rgb radiance{1, 1, 1};              // 0 for an image
  std::string file;                   // as written in the scene (empty: constant radiance)
  double intensity = 1.0;             // multiplies the image
  Transform transform;                // rotations only
  std::shared_ptr<const EnvMap> map;  // loaded by load_scene
};
// A point light limited to a cone (docs/scene-format.md, "spot"): intensity times the smooth edge
// spot_falloff() (scene/lights.h), with no cosine-to-axis factor. Positions and directions in the world
// (the light's transform is applied when the scene is read).
struct SpotLight {
  Vec3 position{0, 0, 5};
  Vec3 direction{0, 0, -1};      // the cone's axis, unit
  Rgb intensity{1, 1, 1};        // W/sr on the axis
  double cone_angle_deg = 45.0;  // the full angle, in (0, 180]
  double blend = 0.0;            // in [0, 1]
};
// Area lights: a sphere emitting `radiance` outward from every point of its surface, and a one-sided
// rectangle (`size` across normal x up and along up) emitting along its normal. `power` in the scene is
// turned into radiance when it is read. `visible`: camera rays see them. They occlude nothing.
struct SphereLight {
  Vec3 center{0, 0, 0};
  double radius = 1.0;
  Rgb radiance{1, 1, 1};
  bool visible = false;
};
struct RectangleLight {
  Vec3 center{0, 0, 0};
  Vec3 normal{0, 0, -1};  // unit; light leaves this side
  Vec3 up{0, 1, 0};       // unit, perpendicular to normal
  double width = 1.0, height = 1.0;
  Rgb radiance{1, 1, 1};
  bool visible = false;
};
using Light =
    std::variant<DirectionalLight, PointLight, EnvironmentLight, SpotLight, SphereLight, RectangleLight>;

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

// The spp an integrator renders with when the scene and the command line give none: the one with the
// best error per second. pathtrace's error falls as 1 / sqrt(spp) at a cost in proportion to spp (any
// spp has the same efficiency; 64 is a first look); the deterministic marches' error is mostly their
// bias, which more samples do not reduce: 4 spp (anti-aliasing and the march's jitter) is where their
// error stops falling on the validation suite (docs/validation/render.md). `mfs`'s error is its bias and
// its photon grids' noise, fixed per render: over the suite at 128 x 128 its error^2 x CPU is least at
// 1 spp in 4 x 4-pixel bins and at 2-4 spp pixel by pixel; 2 spp is within 20 % of the best in bins on
// all nine scenes and within 25 % pixel by pixel on eight, 4 spp up to 64 % off in bins
// (docs/benchmarks.md, "`mfs`'s default spp").
inline int default_spp(const std::string& integrator) {
  return integrator == "pathtrace" ? 64 : integrator == "mfs" ? 2 : 4;
}

struct IntegratorSettings {
  std::string type = "pathtrace";
  int spp = 64;
  bool spp_given = false;  // the scene names its spp (else default_spp(type))
  int max_events = 0;      // most scattering events on a path; 0 = unlimited
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
// A transient render's time bins (film.time_bins [t0, t1, N]): N equal bins of total path length from
// the light to the camera over [t0, t1), in scene units (c = 1). docs/transient.md.
struct TimeBins {
  double t0 = 0.0, t1 = 0.0;
  int count = 0;
};
// At most this many time bins, and at most this many doubles (width x height x (N + 2) x 3) of
// time-binned sums (4 GiB).
inline constexpr int kMaxTimeBins = 100000;
inline constexpr double kMaxTimeBinValues = 512.0 * 1024 * 1024;

struct FilmSettings {
  bool transparent = false;
  std::vector<std::string> layers;
  std::optional<TimeBins> time_bins;  // absent: a steady-state render only
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
// naming the file and the JSON path: "scene.json: /media/0/sigma_s: must be >= 0". `overrides`
// (apply_scene_override) change the document before it is validated, as if written in the file.
Scene load_scene(const std::filesystem::path& file, const std::vector<std::string>& overrides = {});
// A scene file's JSON document, not yet validated.
nlohmann::json read_scene_document(const std::filesystem::path& file);
// Sets one field of a scene document from "PATH=VALUE" (render --set): PATH is object keys and array
// indices separated by dots ("camera.width", "media.0.sigma_s"; a missing key is added, with objects
// made on the way), VALUE is read as JSON when it parses as JSON (2, [1, 0, 0], true, "x") and as a
// string otherwise (cloud.vdb). Throws nimbus::Error naming the override for a malformed assignment, an
// index past the end of an array, or a path through a number or string.
void apply_scene_override(nlohmann::json& doc, const std::string& assignment);
// The built-in demo's document.
nlohmann::json builtin_demo_document();
// The same from an in-memory document; `name` stands for the file in messages, relative volume
// paths resolve against `base_dir`.
Scene parse_scene(const nlohmann::json& doc, const std::string& name, const std::filesystem::path& base_dir);
// The built-in demo: a procedural cloud under a sun and a blue sky.
Scene builtin_demo_scene();

// Limits on what a scene may ask for (checked by the parser, documented in docs/scene-format.md).
inline constexpr int kMaxImageSide = 16384;
inline constexpr int64_t kMaxImagePixels = int64_t(1) << 26;  // 64 Mpixel: ~1.5 GiB of float buffers
inline constexpr int kMaxSpp = 1 << 24;
// The most samples one pixel sample of an outline pixel may take (mfs's edge_samples): a pixel's samples
// (kMaxSpp x this at most) stay below 2^31.
inline constexpr int kMaxEdgeSamples = 64;

}  // namespace nimbus
