// A pulsed lidar looking into a scene's media (issue 14, section 2; docs/validation/lidar.md): the
// heterogeneous counterpart of transport/lidar.h's slab.
//
// Geometry.  A pulse of one photon leaves `origin` at t = 0 along `dir` (unit).  The receiver is a disk
// of radius r_rx (0: a point) centred on the origin, facing `dir`, that accepts light arriving within the
// half-angle fov of -dir.  Time = n * path length (c = 1 in vacuum; n scales time only: no refraction).
// Value per time bin: energy per unit receiver area per source photon [1/length^2], as the slab lidar.
// The media are monochromatic here: one channel (`channel`, 0..2: r, g, b) of the scene's coefficients.
// Surfaces, lights and the camera of the scene play no part (the CLI refuses scenes with surfaces).
//
// Two answers:
//  - `run_scene_lidar_mc`: photon Monte Carlo, the judge.  Delta tracking against the renderer's
//    majorant grid (integrators/tracking.h), absorption carried as weight (w *= sigma_s / sigma_t at each
//    real collision), the phase function of the medium chosen in proportion to its sigma_s; at every
//    scattering event a next-event estimate to a point drawn uniformly on the receiver disk, with the
//    return leg's transmittance estimated without bias by ratio tracking (tracking.h).  Photon k draws
//    from Rng(seed, k): the same bits for any thread count.
//  - `scene_lidar_single_scatter`: the single-scatter lidar equation along the axis,
//        P(R) dR = sigma_s(x) pbar(x) exp(-2 tau(R)) O(R) / R^2 dR,  x = origin + R dir,
//    tau(R) the optical depth from the origin, pbar the sigma_s-weighted p(pi) of the media at x, and the
//    slab's overlap O(R) = min(1, (R tan fov / r_rx)^2); by quadrature (midpoint rule, 256 steps per bin).
#pragma once

#include <cstdint>
#include <vector>

#include "core/math.h"
#include "scene/context.h"
#include "transport/lidar.h"

namespace nimbus {

struct SceneLidarSettings {
  Vec3 origin{0.0, 0.0, 0.0};
  Vec3 dir{0.0, 0.0, 1.0};  // normalised by validate_scene_lidar's caller
  int channel = 1;
  double n = 1.0;                  // time = n * path length
  double r_rx = 0.0;               // receiver radius [length], >= 0
  double fov = 0.01;               // receiver half-angle [rad], in (0, pi/2)
  std::vector<double> time_edges;  // [length], >= 2, increasing, >= 0
  // Monte Carlo only:
  uint64_t photons = 100000;
  uint64_t seed = 1;
  int batches = 20;
};

struct SceneLidarResult {
  TimeTally received;  // next-event estimate per time bin [1/length^2 per photon]
  Estimate total;      // its sum over all times
};

// Throws nimbus::Error naming the setting on invalid input (dir must be unit length).
void validate_scene_lidar(const SceneLidarSettings& s, bool monte_carlo);

SceneLidarResult run_scene_lidar_mc(const SceneContext& ctx, const SceneLidarSettings& s);

// Per bin [1/length^2 per photon].
std::vector<double> scene_lidar_single_scatter(const SceneContext& ctx, const SceneLidarSettings& s);

}  // namespace nimbus
