// nimbus lidar --scene (cmd_lidar_scene.h).
#include "cmd_lidar_scene.h"

#include <fmt/format.h>

#include <limits>

#include "integrators/lidar_scene.h"
#include "nimbus/error.h"
#include "nimbus/scene.h"
#include "scene/context.h"
#include "transport/phase_spec.h"

namespace nimbus::cli {

namespace {

Vec3 vector_option(const std::string& option, const std::string& text) {
  const std::vector<double> v = parse_number_list(option, text);
  if (v.size() != 3) throw Error(fmt::format("{}: expected x,y,z (got {} numbers)", option, v.size()));
  return Vec3(v[0], v[1], v[2]);
}

SceneLidarSettings scene_lidar_settings(const SceneLidarRequest& r) {
  SceneLidarSettings s;
  s.origin = vector_option("--origin", r.origin);
  const Vec3 d = vector_option("--dir", r.dir);
  if (!(length(d) > 0.0) || !std::isfinite(length(d))) throw Error("--dir must be finite and not zero");
  s.dir = normalize(d);
  if (r.channel < 0 || r.channel > 2)
    throw Error(fmt::format("--channel must be 0, 1 or 2 (got {})", r.channel));
  s.channel = r.channel;
  s.n = r.n;
  s.fov = r.fov;
  s.r_rx = r.r_rx;
  s.photons = r.photons;
  s.seed = r.seed;
  s.time_edges = r.time_edges;
  validate_scene_lidar(s, true);
  return s;
}

}  // namespace

void scene_lidar_rows(const SceneLidarRequest& request, const LidarRowFn& row) {
  const SceneLidarSettings s = scene_lidar_settings(request);
  const Scene scene = load_scene(request.scene);
  if (!scene.surfaces.empty())
    throw Error(fmt::format("{}: /surfaces: lidar --scene takes media only", request.scene));
  if (scene.media.empty())
    throw Error(fmt::format("{}: /media: lidar --scene needs a medium", request.scene));
  const SceneContext ctx(scene);
  const std::vector<double>& e = s.time_edges;
  for (const std::string& m : request.models) {
    if (m == "mc") {
      const SceneLidarResult r = run_scene_lidar_mc(ctx, s);
      if (e.front() > 0.0) row(m, 0.0, e.front(), r.received.before.value, r.received.before.err);
      for (size_t i = 0; i + 1 < e.size(); ++i)
        row(m, e[i], e[i + 1], r.received.bins[i].value, r.received.bins[i].err);
      row(m, e.back(), std::numeric_limits<double>::infinity(), r.received.after.value, r.received.after.err);
    } else {
      const std::vector<double> v = scene_lidar_single_scatter(ctx, s);
      for (size_t i = 0; i + 1 < e.size(); ++i) row(m, e[i], e[i + 1], v[i], 0.0);
    }
  }
}

}  // namespace nimbus::cli
