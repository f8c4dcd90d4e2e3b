// Photon Monte Carlo for a pencil beam entering a medium normally at the origin along +z: the reference
// that judges every propagator in src/transport/, and the slab tool (`nimbus slab`).
//
// Geometry: an infinite medium (thickness = infinity; the beam starts inside it at z = 0), or a slab
// [0, D] of refractive index n against 1 outside (n = 1: matched boundaries).
// Conventions follow MCML (Wang, Jacques & Zheng 1995), re-implemented from the paper's description:
//  - specular reflection at entry, Rsp = ((n - 1)/(n + 1))^2, is tallied as `specular`; the photon
//    enters with weight 1 - Rsp;
//  - free paths with sigma_t = sigma_s + sigma_a; at each interaction the fraction sigma_a / sigma_t of
//    the weight is deposited (absorbed) and the photon scatters with the phase function;
//  - at a face the unpolarised Fresnel reflectance R (total internal reflection beyond the critical
//    angle) splits the weight: w (1 - R) leaves (refracted), w R is reflected and goes on;
//  - Russian roulette below weight 1e-4 with survival 0.1 (weight / 0.1): unbiased.
//  - in the infinite medium photons also meet a depth roulette that keeps expectations: each time a
//    photon first reaches one more transport length beyond the deepest tally plane (or behind the
//    source), it survives with probability 1/2 and doubles its weight.
// Tallies (all per source photon):
//  - at each plane z_k every crossing counts (forward and backward); scattered light goes to
//    angular bins of the polar angle theta of propagation, as weight / |cos theta| / bin solid angle
//    (plane-integrated radiance per sr), and forward crossings (cos theta > 0) to radial bins as weight
//    / annulus area (forward flux per unit area); unscattered crossings go to `unscattered` only;
//    the angular tally is also kept for photons that never travelled backward (diagnostic);
//  - slab: diffuse reflectance (everything leaving the top face, i.e. all but the specular part, also
//    unscattered light reflected at the bottom face), transmittance (everything leaving the bottom face,
//    unscattered included) and unscattered transmittance apart, absorbed weight; exits also resolved in
//    exit angle outside (weight per sr of exit solid angle, MCML's Rd_a / Tt_a) and radius (per area).
// Time (issue 14; with time_edges): a photon's time is n times its path length in the medium (c = 1 in
// vacuum).  Exits are binned by their time (reflect_time, transmit_time: weight per bin, per source
// photon, not per unit time), and scattered forward crossings (cos theta > 0) of each plane z_k by their
// delay n (s - z_k), with the weighted moments of that delay, and (joint_angle, joint_radius) by delay
// and angle or delay and radius.  Every tallied event lands in exactly one
// bin or in `before`/`after`, so the bins with those two sum to the steady tally of the same photons.
// Determinism: photon i draws from Rng(seed, i), photons are grouped in batches (standard errors from
// the spread of batch means) and batches are summed in order, so results do not depend on threads.
#pragma once

#include <cstdint>
#include <limits>
#include <vector>

#include "media/phase.h"

namespace nimbus {

struct PhotonMcSettings {
  double sigma_s = 1.0;  // [1/length]
  double sigma_a = 0.0;  // [1/length]
  Phase phase = HgPhase{0.9};
  double thickness = std::numeric_limits<double>::infinity();  // slab [0, D]; infinity = infinite medium
  double n = 1.0;                                              // slab refractive index (1 outside)
  std::vector<double> plane_depths;                            // [length], > 0 (and < thickness), increasing
  std::vector<double> theta_edges;  // [rad], increasing in [0, pi]: plane angular bins and exit bins
  std::vector<double> r_edges;      // [length], increasing, >= 0: plane radial bins and exit bins
  uint64_t photons = 100000;
  uint64_t seed = 1;
  int batches = 16;                // >= 10 for standard errors
  std::vector<double> time_edges;  // [length]; empty: no time tallies; else >= 2, increasing, >= 0
  // Joint tallies (need time_edges): scattered forward crossings of each plane by delay and polar angle,
  // and by delay and radius (PlaneTally::delay_angle, delay_radius).
  bool joint_angle = false, joint_radius = false;
};

struct Estimate {
  double value = 0.0;
  double err = 0.0;  // standard error of the mean from batches
};

// Tallies binned in time (or delay): bins of time_edges, and the parts before the first and after the last.
struct TimeTally {
  std::vector<Estimate> bins;
  Estimate before, after;
};

struct PlaneTally {
  double depth = 0.0;
  std::vector<Estimate> angular;  // per sr, plane-integrated scattered radiance (bins of theta_edges)
  std::vector<Estimate> radial;   // per unit area, forward scattered flux (bins of r_edges)
  // Diagnostic: the part of `angular` carried by photons that never travelled backward (cos theta <= 0)
  // before the crossing, the light a small-angle model describes.
  std::vector<Estimate> angular_forward_only;
  Estimate unscattered;  // unscattered flux through the plane
  // With time_edges: scattered forward crossings by delay n (s - z) (weight per bin), their total weight,
  // and the weighted mean and variance of the delay (errors from the spread of batch values); the same
  // moments of the photons that never travelled backward (the light a small-angle model describes: in an
  // infinite medium rare photons that wander deep and return dominate the moments of all the light).
  TimeTally delay;
  Estimate delay_weight, delay_mean, delay_variance;
  Estimate delay_mean_forward_only, delay_variance_forward_only;
  // The part of `delay` (bins, before, after) and of delay_weight carried by those photons.
  TimeTally delay_forward_only;
  Estimate delay_weight_forward_only;
  // Joint tallies (joint_angle, joint_radius): the same crossings as `delay`, weight per delay bin per
  // source photon, for each bin of theta_edges (delay_angle[i]) or r_edges (delay_radius[i]) and, last,
  // for the crossings outside those edges.  Summed over the angle (or radius) entries they are `delay`;
  // summed over time, delay_radius[i] is radial[i] times the annulus area, and delay_angle[i] is the
  // forward flux of the bin (angular[i] times its solid angle and a cos theta of the bin).
  std::vector<TimeTally> delay_angle, delay_radius;
};

struct PhotonMcResult {
  std::vector<PlaneTally> planes;
  Estimate specular, diffuse_reflectance, transmittance, unscattered_transmittance, absorbed;
  // Exit-resolved slab tallies: exit polar angle outside (per sr) and exit radius (per area).
  std::vector<Estimate> reflect_angular, reflect_radial, transmit_angular, transmit_radial;
  // With time_edges: diffuse reflectance and transmittance (unscattered included) by exit time.
  TimeTally reflect_time, transmit_time;
};

// Throws nimbus::Error on invalid settings.  Multithreaded (oneTBB), deterministic for a seed.
PhotonMcResult run_photon_mc(const PhotonMcSettings& settings);

// Unpolarised Fresnel reflectance for light inside index n_i meeting an interface to index n_t with
// cos_i = |cos| of the angle of incidence; 1 beyond the critical angle.  Sets *cos_t when not null.
double fresnel_reflectance(double n_i, double n_t, double cos_i, double* cos_t = nullptr);

}  // namespace nimbus
