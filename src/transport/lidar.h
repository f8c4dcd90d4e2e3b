// A pulsed lidar looking into a homogeneous slab (issue 14, section 2; docs/validation/lidar.md).
//
// Geometry.  The slab fills distance <= z <= distance + thickness (matched boundaries: the refractive
// index n only scales time); between the lidar and the slab lies a clear gap of the same index (a cloud
// base above a ground lidar; 0 for a lidar at the face).  A pulse of one photon leaves the origin at t = 0
// along +z.  The receiver is a disk of radius
// r_rx (0: a point) in the plane z = 0, centred on the axis, that accepts light arriving within the
// half-angle fov of -z.  Time = n * path length (out and back; c = 1 in vacuum).
// Received power: energy per unit receiver area (the disk's mean irradiance) per source photon that
// arrives in each time bin (not per unit time: divide by the bin width for a rate), in 1/length^2.
//
// Three answers:
//  - `run_lidar_mc`: photon Monte Carlo, the judge.  Next-event (local) estimation toward the receiver
//    at every scattering event (a point drawn uniformly on the disk, the phase function toward it, the
//    return leg's exp(-sigma_t L), the receiver's cos / L^2 and its FOV), plus an analog tally of the
//    photons that leave the top face into the disk within the FOV (an independent steady estimate).
//  - `lidar_single_scatter`: the single-scatter lidar equation b p(pi) exp(-2 c (R - distance)) / R^2 dR
//    at range R = t / 2n, with the receiver's overlap min(1, (R tan fov / r_rx)^2); closed form with E1.
//  - `lidar_mfs`: the seed's fused algorithm in time (lidar_model.cpp): the outgoing beam and, by
//    reciprocity, the receiver's beam carried by the corrected MFS propagator (spread in angle, space and
//    delay), one back scatter with the full p(pi - angle), the two legs' delays added, nothing before 2 n z.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "core/rng.h"
#include "media/phase.h"
#include "transport/photon_mc.h"

namespace nimbus {

struct LidarSettings {
  double sigma_s = 1.0;  // [1/length]
  double sigma_a = 0.0;  // [1/length]
  Phase phase = HgPhase{0.9};
  double thickness = 1.0;  // [length], finite
  double distance = 0.0;   // from the lidar to the slab's near face [length], >= 0
  double n = 1.0;          // time = n * path length
  // A Fresnel top face (air above, index n below): the gap is air (time = gap + n * path in the slab),
  // the surface reflects (exact unpolarised Fresnel) and refracts; needs distance > 0.  Models: mc and
  // single (the fused model refuses it).  The bottom face stays matched.
  bool fresnel = false;
  double r_rx = 0.0;               // receiver radius [length], >= 0
  double fov = 0.01;               // receiver half-angle [rad], in (0, pi/2)
  std::vector<double> time_edges;  // [length], >= 2, increasing, >= 0
  // Monte Carlo only:
  uint64_t photons = 100000;
  uint64_t seed = 1;
  int batches = 20;
};

struct LidarMcResult {
  TimeTally received;  // next-event estimate per time bin [1/length^2 per photon]
  Estimate total;      // its sum over all times (bins, before and after)
  Estimate analog;     // independent: photons leaving the top face into the disk within the FOV / area
};

// Throws nimbus::Error naming the setting on invalid input.
void validate_lidar(const LidarSettings& s, bool monte_carlo);
// The checks both lidars (slab and scene) share, with the same messages: refractive index, receiver
// radius and field of view, time edges; and the Monte Carlo's photons and batches.
void validate_lidar_receiver(double n, double r_rx, double fov, const std::vector<double>& time_edges);
void validate_lidar_batches(uint64_t photons, int batches);

// Deterministic for a seed, whatever the number of threads (photon i draws from Rng(seed, i)).
LidarMcResult run_lidar_mc(const LidarSettings& s);

// The photon driver of both lidars (this slab's and the scene's, integrators/lidar_scene.h): `photons`
// histories in `batches`, photon k drawing from Rng(seed, k), trace(rng, acc) adding to acc[0, slots);
// batches summed in order, so the result has the same bits for any thread count.  Each slot's mean per
// photon with its batch standard error, and the same for the sum of the first `summed` slots.
// The accumulator slot of time t: 0 before edges[0], i for [edges[i-1], edges[i]), edges.size() after.
size_t lidar_time_slot(const std::vector<double>& edges, double t);

struct BatchTally {
  std::vector<Estimate> slots;
  Estimate sum;
};
BatchTally run_photon_batches(uint64_t photons, int batches, uint64_t seed, size_t slots, size_t summed,
                              const std::function<void(Rng&, double*)>& trace);

// The surface's specular return with a Fresnel face: R(0) per photon arriving at t = 2 distance, as energy
// per unit receiver area (R(0) / (pi r_rx^2); infinite for a point receiver, which it hits).
double lidar_surface_return(const LidarSettings& s);

// The single-scatter lidar equation per bin [1/length^2 per photon] (see above).
std::vector<double> lidar_single_scatter(const LidarSettings& s);

// The fused small-angle model per bin, and its parts.
struct LidarModelResult {
  std::vector<double> bins;          // all orders of the model
  std::vector<double> single;        // its unscattered-unscattered term (the single-scatter equation)
  double before = 0.0, after = 0.0;  // before the first edge, at or after the last
};
LidarModelResult lidar_mfs(const LidarSettings& s);

// Area of the intersection of two disks of radii r1, r2 whose centres are d apart.
double disk_overlap_area(double r1, double r2, double d);

}  // namespace nimbus
