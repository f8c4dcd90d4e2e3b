// nimbus lidar --scene: the lidar looking into a scene's media (src/integrators/lidar_scene.h), apart from
// cmd_lidar.cpp, which parses the options and runs the slab lidar.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace nimbus::cli {

// The options of `lidar --scene`, the receiver's already checked by cmd_lidar.cpp.
struct SceneLidarRequest {
  std::string scene, origin, dir;  // the scene file; origin and dir as "x,y,z"
  int channel = 1;
  double n = 1.0, fov = 0.01, r_rx = 0.0;
  uint64_t photons = 0, seed = 1;
  std::vector<double> time_edges;
  std::vector<std::string> models;  // mc, single
};

// One CSV row: model, tlo, thi, value, stderr.
using LidarRowFn = std::function<void(const std::string&, double, double, double, double)>;

// Loads the scene (errors name the file and the field), checks origin, dir and channel, and hands each
// model's rows to `row`.
void scene_lidar_rows(const SceneLidarRequest& request, const LidarRowFn& row);

}  // namespace nimbus::cli
