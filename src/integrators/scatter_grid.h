// The light that has already taken at least one wide (large-angle) scatter, for `mfs` with
// large_angle_scatters > 1: the higher orders of the seed's picture.
//
// The phase function of every medium is split P = f P_peak + (1 - f) P_wide (transport/phase_split.h).
// In the similarity (delta-scaling) picture peak scatters leave light on its way and wide scatters are
// the events: extinction sigma_a + (1 - f) sigma_s, scattering (1 - f) sigma_s with P_wide. Photons
// from every light are traced through that medium (delta tracking against the majorant grid, wide
// directions drawn exactly from P_wide by rejection from P), and every flight after the first wide
// scatter, and before the K-th, deposits its track length (the track-length estimator of fluence,
// unbiased) into a coarse node grid, with the first angular moment:
//     phi(x) = int L(x, w) dw,   F(x) = int L(x, w) w dw      (w: direction of travel).
// `mfs` adds one more wide scatter at each march point y towards the camera (travel direction w_o):
//     sigma_s (1 - f) int P_wide(w . w_o) L(y, w) dw ~ sigma_s (1 - f) (phi + 3 g_wide F . w_o) / (4 pi),
// the first two spherical-harmonic bands of L (exact for the isotropic and linear parts; light after
// wide scatters is smooth in angle), clamped at zero.
//
// Deterministic: photon i uses its own random stream; photons are split into a fixed number of
// batches (each its own grid, summed in order), so the grid does not depend on the thread count.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "integrators/integrator.h"
#include "transport/phase_split.h"

namespace nimbus {

struct ScatterGridSettings {
  int photons = 1 << 18;      // per channel pass, shared among the lights
  int resolution = 32;        // nodes along the longest axis of the media's bounds
  int max_wide_scatters = 0;  // K: flights after wide scatter 1 .. K-1 are kept; 0 = all orders
  uint64_t seed = 1;
};

class ScatterGrid {
 public:
  // splits[i], peak_fraction[i]: medium i's phase split (as `mfs` uses it).
  ScatterGrid(const SceneContext& ctx, const std::vector<const PhaseSplit*>& splits,
              const std::vector<double>& peak_fraction, const ScatterGridSettings& settings);

  // Fluence and flux (per channel) at p, trilinear between nodes (zero outside the grid).
  void lookup(const Vec3& p, Rgb* phi, std::array<Rgb, 3>* flux) const;
  // (phi + 3 g F . w_out) / (4 pi) per channel, clamped at zero: the radiance a unit of wide scattering
  // with mean cosine g (per channel) sends along w_out, per unit scattering coefficient.
  Rgb scattered(const Vec3& p, const Vec3& w_out, const Rgb& g) const;

  size_t memory_bytes() const { return values_.size() * sizeof(float); }
  const std::array<int, 3>& nodes() const { return nodes_; }
  double photons_traced() const { return photons_traced_; }

 private:
  Bounds bounds_;  // of the node grid (the media's bounds padded by one spacing)
  std::array<int, 3> nodes_{2, 2, 2};
  Vec3 spacing_{1.0};
  std::vector<float> values_;  // per node: channel c at [4 c]: phi, F.x, F.y, F.z
  double photons_traced_ = 0.0;
};

}  // namespace nimbus
