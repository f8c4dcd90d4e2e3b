// Scene JSON: parsing and validation (docs/scene-format.md is the user-facing description).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/json_reader.h"
#include "integrators/registry.h"
#include "io/scene_emission.h"
#include "io/scene_environment.h"
#include "io/scene_fields.h"
#include "io/scene_lights.h"
#include "io/scene_surfaces.h"
#include "io/scene_volumes.h"
#include "io/transform_json.h"
#include "media/fournier_forand.h"
#include "media/media.h"
#include "media/phase.h"
#include "nimbus/error.h"
#include "nimbus/render.h"
#include "nimbus/scene.h"
#include "transport/phase_spec.h"

namespace nimbus {

namespace {

double g_value(JsonObject& o, const std::string& key, double fallback) {
  const double g = o.number(key, -1e300, 1e300, fallback);
  if (!(std::abs(g) < 1.0)) o.fail(key, "must satisfy |g| < 1");
  return g;
}

Phase parse_phase(JsonObject o) {
  const std::string type = o.string("type");
  Phase phase;
  if (type == "isotropic") {
    phase = IsotropicPhase{};
  } else if (type == "hg") {
    phase = HgPhase{g_value(o, "g", 0.0)};
  } else if (type == "double_hg") {
    DoubleHgPhase p;
    p.g1 = g_value(o, "g1", 0.0);
    p.g2 = g_value(o, "g2", 0.0);
    p.w = o.number("w", 0.0, 1.0);
    phase = p;
  } else if (type == "gauss") {
    phase = make_gauss_phase(o.number_open_below("theta2", 0.0, 100.0));
  } else if (type == "fournier_forand") {
    const double n = o.number_open_below("n", 1.0, 1.5), mu = o.number_open_below("mu", 3.0, 5.0);
    phase = make_ff_phase(n, mu);
  } else if (type == "mie") {
    // A table shipped in data/phase, by name (not a path: a scene's header must render the same anywhere).
    const std::string table = o.string("table");
    if (!is_phase_table_name(table))
      o.fail("table", fmt::format("'{}' is not a table name (letters, digits, '_', '-', '.'; e.g. "
                                  "\"cloud_mie_550nm\", a table of {})",
                                  table, phase_table_dir()));
    const std::string path = phase_table_dir() + "/" + table + ".csv";
    if (!std::filesystem::is_regular_file(path))
      o.fail("table", fmt::format("no table '{}' ({} does not exist)", table, path));
    try {
      phase = load_phase_table(table, path);
    } catch (const Error& e) {
      o.fail("table", e.what());
    }
  } else {
    o.fail("type", fmt::format("unknown phase function '{}' (known: isotropic, hg, double_hg, gauss, "
                               "fournier_forand, mie)",
                               type));
  }
  o.finish();
  return phase;
}

Shape parse_shape(JsonObject o, const std::filesystem::path& base_dir, const VolumeTable& volumes) {
  const std::string type = o.string("type");
  Shape shape;
  if (type == "sphere") {
    SphereShape s;
    s.center = o.vec3("center", s.center);
    s.radius = o.number_open_below("radius", 0.0, 1e30);
    shape = s;
  } else if (type == "box") {
    BoxShape b;
    read_box_corners(o, &b.min, &b.max);
    shape = b;
  } else if (type == "vdb") {
    VdbShape v;
    const bool in_memory = o.has("volume");  // a `file`, or else an in-memory `volume`
    std::string volume;
    if (in_memory) {
      volume = o.string("volume");
      if (volume.empty()) o.fail("volume", "must name an in-memory volume");
      if (o.has("file")) o.fail("volume", "give either a file or a volume, not both");
    } else {
      v.file = o.string("file");
    }
    v.grid = o.string("grid", "");
    v.translate = o.vec3("translate", v.translate);
    v.scale = o.number_open_below("scale", 0.0, 1e30, v.scale);
    if (!in_memory) {
      load_vdb_shape(v, base_dir, o.where(), o.path());
    } else {
      if (o.has("grid")) o.fail("grid", "an in-memory volume has one grid; name none");
      const auto it = volumes.find(volume);
      if (it == volumes.end())
        o.fail("volume", fmt::format("no in-memory volume named '{}' (in-memory volumes come from the "
                                     "Python module: docs/python.md; a scene file names a `file`)",
                                     volume));
      v.data = it->second;
    }
    shape = v;
  } else if (type == "cloud") {
    CloudShape c;
    c.center = o.vec3("center", c.center);
    c.radius = o.number_open_below("radius", 0.0, 1e30);
    c.seed = uint32_t(o.integer("seed", 0, 0xffffffffll, 1));
    c.resolution = int(o.integer("resolution", 8, 1024, 128));
    build_cloud_shape(c);
    shape = c;
  } else {
    o.fail("type", fmt::format("unknown shape '{}' (known: sphere, box, vdb, cloud)", type));
  }
  o.finish();
  return shape;
}

Medium parse_medium(JsonObject o, const std::filesystem::path& base_dir, const VolumeTable& volumes) {
  Medium m;
  m.shape = parse_shape(o.object("shape"), base_dir, volumes);
  m.transform = parse_optional_transform(o);
  m.sigma_s = o.rgb("sigma_s", 0.0);
  m.sigma_a = o.rgb("sigma_a", 0.0, Rgb(0.0));
  m.phase = o.has("phase") ? parse_phase(o.object("phase")) : Phase{IsotropicPhase{}};
  parse_medium_emission(o, m, base_dir);  // io/scene_emission.cpp
  o.finish();
  return m;
}

Camera parse_camera(JsonObject o) {
  Camera c;
  c.position = o.vec3("position");
  c.look_at = o.vec3("look_at");
  c.up = o.vec3("up", c.up);
  c.fov_y_deg = o.number_open_below("fov_y_deg", 0.0, 179.0);
  c.width = int(o.integer("width", 1, kMaxImageSide));
  c.height = int(o.integer("height", 1, kMaxImageSide));
  if (int64_t(c.width) * c.height > kMaxImagePixels)
    o.fail("height", fmt::format("width x height exceeds the limit of {} pixels", kMaxImagePixels));
  const Vec3 forward = c.look_at - c.position;
  if (!(length(forward) > 1e-12)) o.fail("look_at", "must differ from position");
  if (!(length(c.up) > 1e-12)) o.fail("up", "must have non-zero length");
  if (length(cross(normalize(forward), normalize(c.up))) < 1e-6)
    o.fail("up", "must not be parallel to the view direction (look_at - position)");
  o.finish();
  return c;
}

IntegratorSettings parse_integrator(const nlohmann::json& j, JsonObject o) {
  IntegratorSettings s;
  s.type = o.string("type", s.type);
  s.spp_given = j.contains("spp");
  s.spp = int(o.integer("spp", 1, kMaxSpp, default_spp(s.type)));
  s.max_events = int(o.integer("max_events", 0, 1000000, s.max_events));
  s.seed = uint64_t(o.integer("seed", 0, int64_t(1) << 53, int64_t(s.seed)));
  const std::vector<std::string> known = integrator_names();
  if (std::find(known.begin(), known.end(), s.type) == known.end())
    o.fail("type", fmt::format("unknown integrator '{}' (known: {})", s.type, fmt::join(known, ", ")));
  // The remaining fields belong to the integrator, which checks them.
  for (auto it = j.begin(); it != j.end(); ++it) {
    if (it.key() != "type" && it.key() != "spp" && it.key() != "max_events" && it.key() != "seed")
      s.options[it.key()] = it.value();
  }
  validate_integrator_options(s.type, s.options, o.where());
  return s;
}

// film.time_bins [t0, t1, N]: 0 <= t0 < t1 finite, 1 <= N <= kMaxTimeBins, and the time-binned sums of a
// width x height image within kMaxTimeBinValues.
TimeBins parse_time_bins(JsonObject& o, const Camera& camera) {
  const nlohmann::json& v = o.raw("time_bins");
  const char* form = "must be [t0, t1, N]: N equal bins of path length over [t0, t1), 0 <= t0 < t1, N >= 1";
  if (!v.is_array() || v.size() != 3 || !v[0].is_number() || !v[1].is_number() || !v[2].is_number())
    o.fail("time_bins", form);
  TimeBins b{v[0].get<double>(), v[1].get<double>(), 0};
  if (!(b.t0 >= 0.0 && b.t1 > b.t0 && std::isfinite(b.t1))) o.fail("time_bins", form);
  const double n = v[2].get<double>();
  if (!(n >= 1.0 && n <= kMaxTimeBins && n == std::floor(n)))
    o.fail("time_bins", fmt::format("N (the third entry) must be an integer in [1, {}]", kMaxTimeBins));
  b.count = int(n);
  const double values = double(camera.width) * camera.height * (b.count + 2) * 3;
  if (values > kMaxTimeBinValues)
    o.fail("time_bins", fmt::format("{} bins of a {}x{} image need {:.1f} GiB of sums (at most {:.0f})",
                                    b.count, camera.width, camera.height, values * 8 / (1 << 30),
                                    kMaxTimeBinValues * 8 / (1 << 30)));
  return b;
}

FilmSettings parse_film(JsonObject o, const Camera& camera) {
  FilmSettings f;
  if (o.has("time_bins")) f.time_bins = parse_time_bins(o, camera);
  f.transparent = o.boolean("transparent", f.transparent);
  if (o.has("layers")) {
    const nlohmann::json& layers = o.raw("layers");
    if (!layers.is_array()) o.fail("layers", "must be an array of layer names");
    const std::vector<std::string>& known = film_layer_names();
    for (size_t i = 0; i < layers.size(); ++i) {
      const std::string key = fmt::format("layers/{}", i);
      if (!layers[i].is_string()) o.fail(key, "must be a layer name (a string)");
      const std::string name = layers[i].get<std::string>();
      if (std::find(known.begin(), known.end(), name) == known.end())
        o.fail(key, fmt::format("unknown layer '{}' (known: {})", name, fmt::join(known, ", ")));
      if (std::find(f.layers.begin(), f.layers.end(), name) != f.layers.end())
        o.fail(key, fmt::format("layer '{}' named twice", name));
      f.layers.push_back(name);
    }
  }
  o.finish();
  return f;
}

}  // namespace

Scene parse_scene(const nlohmann::json& doc, const std::string& name, const std::filesystem::path& base_dir) {
  return parse_scene(doc, name, base_dir, VolumeTable{});
}

Scene parse_scene(const nlohmann::json& doc, const std::string& name, const std::filesystem::path& base_dir,
                  const VolumeTable& volumes) {
  JsonObject root(doc, name, "");
  Scene scene;
  scene.camera = parse_camera(root.object("camera"));
  std::vector<JsonObject> media = root.array_of_objects("media", true);
  // Checked before any volume is loaded or voxelised (the renderer would refuse the scene anyway).
  if (media.size() > size_t(kMaxMedia))
    root.fail("media", fmt::format("at most {} media (got {})", kMaxMedia, media.size()));
  for (JsonObject& m : media) scene.media.push_back(parse_medium(m, base_dir, volumes));
  if (root.has("surfaces"))
    for (JsonObject& s : root.array_of_objects("surfaces", true))
      scene.surfaces.push_back(parse_surface(s, base_dir));
  for (JsonObject& l : root.array_of_objects("lights", true)) {
    scene.lights.push_back(parse_light(l, base_dir));
    if (count_environment_images(scene.lights) > 1)
      l.fail("file", "a scene takes at most one environment image");
  }
  if (root.has("integrator"))
    scene.integrator = parse_integrator(doc["integrator"], root.object("integrator"));
  if (root.has("film")) scene.film = parse_film(root.object("film"), scene.camera);
  root.finish();
  scene.source = doc;
  return scene;
}

nlohmann::json read_scene_document(const std::filesystem::path& file) {
  const std::string name = file.string();
  std::error_code ec;
  if (!std::filesystem::exists(file, ec)) throw Error(fmt::format("{}: no such file", name));
  if (std::filesystem::is_directory(file, ec)) throw Error(fmt::format("{}: is a directory", name));
  std::ifstream in(file, std::ios::binary);
  if (!in) throw Error(fmt::format("{}: cannot be opened for reading", name));
  std::ostringstream text;
  text << in.rdbuf();
  const std::string ext = file.extension().string();
  if (ext == ".vdb" || ext == ".nvdb")
    throw Error(
        fmt::format("{}: a volume, not a scene: a scene is a JSON file that names its volumes "
                    "(docs/scene-format.md; `nimbus info {}` describes the volume)",
                    name, name));
  nlohmann::json doc;
  const std::string str = text.str();
  try {
    doc = nlohmann::json::parse(str);
  } catch (const nlohmann::json::parse_error& e) {
    // Where, in lines and columns, rather than nlohmann's byte offset and exception id.
    const size_t at = std::min(e.byte > 0 ? e.byte - 1 : 0, str.size());
    const size_t line = 1 + size_t(std::count(str.begin(), str.begin() + long(at), '\n'));
    const size_t bol = str.rfind('\n', at == 0 ? 0 : at - 1);
    const size_t column = at - (bol == std::string::npos || at == 0 ? 0 : bol + 1) + 1;
    throw Error(
        fmt::format("{}: not valid JSON at line {}, column {} (a scene is a JSON file: "
                    "docs/scene-format.md)",
                    name, line, column));
  } catch (const nlohmann::json::exception& e) {
    throw Error(fmt::format("{}: not valid JSON: {}", name, e.what()));
  }
  return doc;
}

Scene load_scene(const std::filesystem::path& file, const std::vector<std::string>& overrides) {
  nlohmann::json doc = read_scene_document(file);
  for (const std::string& o : overrides) apply_scene_override(doc, o);
  Scene scene = parse_scene(doc, file.string(), file.parent_path());
  scene.file = file;
  return scene;
}

}  // namespace nimbus
