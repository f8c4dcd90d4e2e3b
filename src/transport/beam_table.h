// The `nimbus beam` comparison: a pencil beam into an infinite medium or a slab, tallied at planes of
// given optical depth, by photon Monte Carlo and by every propagator, as rows of one table
// (model, depth, quantity, lo, hi, value, stderr).  Lengths in scattering mean free paths (b = 1).
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "media/phase.h"

namespace nimbus {

struct BeamSettings {
  Phase phase = HgPhase{0.9};
  double albedo = 0.99;        // b / c, in (0, 1]
  std::vector<double> depths;  // optical depths b z of the planes, increasing, > 0
  double thickness = std::numeric_limits<double>::infinity();  // slab [0, D] in mfp, or infinite
  double n = 1.0;                                              // slab refractive index against 1 outside
  uint64_t photons = 1000000;
  uint64_t seed = 1;
  int batches = 20;
  std::vector<double> theta_edges;  // rad; empty: default_theta_edges()
  std::vector<double> r_edges;      // mfp; empty: default_r_edges()
  // Delay-bin edges [mfp] (time_resolved.h); empty: no delay rows.  With them, `mc` adds rows `delay`
  // (scattered forward crossings by delay n (s - z), weight per bin; a last row up to infinity and, if
  // the first edge is > 0, a first row from 0 hold the rest), `delay_mean` and `delay_variance`
  // (lo = hi = 0); `mfs` adds the same rows from its closed form (time_resolved.h), `gsa` from the exact
  // small-angle moments of its deflection law and a moment-matched gamma law (gsa_delay.h); the diagnostic
  // `mc_fwd` adds delay rows, delay_mean and delay_variance of photons that never travelled backward.
  std::vector<double> time_edges;
  // Joint delay x angle and delay x radius tallies of `mc` (need time_edges): rows BeamJointRow.
  bool joint_angle = false, joint_radius = false;
};

struct BeamRow {
  std::string model;  // mc, dolin, tes87, mfs, gsa
  double depth = 0.0;
  std::string
      quantity;  // angular (per sr), radial (per area), unscattered, delay, delay_mean, delay_variance
  double lo = 0.0, hi = 0.0, value = 0.0, stderr_ = 0.0;
};

// A row of a joint table: the weight (per source photon) of the scattered forward crossings of the plane
// at `depth` with delay in [tlo, thi) and polar angle (quantity delay_angle, rad) or radius
// (delay_radius, mfp) in [lo, hi); lo = hi = -1: outside the angle or radius edges.
struct BeamJointRow {
  std::string model;  // mc
  double depth = 0.0;
  std::string quantity;
  double tlo = 0.0, thi = 0.0, lo = 0.0, hi = 0.0, value = 0.0, stderr_ = 0.0;
};

// Bins of polar angle: 2 mrad wide at 0, growing by 12% per bin to 0.1 rad, then 0.1 rad to pi.
std::vector<double> default_theta_edges();
// Bins of radius [mfp]: 2e-3 wide at 0, growing by 15% per bin to 100 mfp.
std::vector<double> default_r_edges();

// All known model names, in output order.
const std::vector<std::string>& beam_model_names();

// Rows for the requested models (each must be one of beam_model_names(), or the diagnostic `mc_fwd`:
// the Monte Carlo's angular tally restricted to photons that never travelled backward).  Models other than `mc`
// describe an infinite medium; in a slab they are scaled by the entry transmission 1 - Rsp.
// Throws nimbus::Error on invalid settings.
// With joint_angle or joint_radius the joint rows go to *joint (which must then be given).
std::vector<BeamRow> beam_table(const BeamSettings& settings, const std::vector<std::string>& models,
                                std::vector<BeamJointRow>* joint = nullptr);

}  // namespace nimbus
