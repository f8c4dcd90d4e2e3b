// The light that has already taken at least one wide (large-angle) scatter, for `mfs` with
// large_angle_scatters > 1: the higher orders of the seed's picture.
//
// The phase function of every medium is split P = f P_peak + (1 - f) P_wide (transport/phase_split.h).
// Photons from every light are traced (delta tracking against the majorant grid) either through the
// true medium (photon_transport "exact", the default: every collision, full phase function, each
// scatter counted as wide with probability (1 - f) P_wide / P) or through the similarity medium
// ("similarity": peak scatters leave light on its way; extinction sigma_a + (1 - f) sigma_s, scattering
// (1 - f) sigma_s with P_wide drawn by rejection from P). Every flight after the first wide scatter,
// and before the K-th, deposits its track length (the track-length estimator of fluence, unbiased) into a
// coarse node grid, as the real spherical-harmonic moments of bands l <= 2:
//     L_lm(x) = int L(x, w) Y_lm(w) dw      (w: direction of travel; L_00 = phi / sqrt(4 pi)).
// `mfs` adds one more wide scatter at each march point y towards the camera (travel direction w_o);
// by Funk-Hecke, with chi_l the Legendre moments of P_wide (chi_0 = 1, chi_1 = g_wide),
//     int P_wide(w . w_o) L(y, w) dw = sum_lm chi_l L_lm(y) Y_lm(w_o),
// truncated at `bands` (default 3: l <= 2; light after wide scatters is smooth in angle) and clamped
// at zero.
//
// The environment (uniform radiance, smooth in angle) is carried by the grid from its entry: its
// flights deposit from order 0, so `mfs` needs no environment sampling on the camera ray.
//
// Deterministic: photon i uses its own random stream; photons are split into a fixed number of
// batches (each its own grid, summed in order), so the grid does not depend on the thread count.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "core/sh.h"
#include "integrators/integrator.h"
#include "transport/phase_split.h"

namespace nimbus {

struct ScatterGridSettings {
  int photons = 1 << 18;        // per channel pass, shared among the lights
  int resolution = 0;           // nodes along the longest axis of the media's bounds; 0: "auto" (mfs)
  int max_wide_scatters = 0;    // K: flights after wide scatter 1 .. K-1 are kept; 0 = all orders
  bool exact_transport = true;  // photons in the true medium (every collision; scatters classified peak
                                // or wide by their share) or (false) in the similarity medium
  int bands = 3;                // spherical-harmonic bands used at lookup: 2 (l <= 1) or 3 (l <= 2)
  uint64_t seed = 1;
};

class ScatterGrid {
 public:
  // splits[i], peak_fraction[i]: medium i's phase split (as `mfs` uses it).
  ScatterGrid(const SceneContext& ctx, const std::vector<const PhaseSplit*>& splits,
              const std::vector<double>& peak_fraction, const ScatterGridSettings& settings);

  // sum_lm chi_l L_lm(p) Y_lm(w_out) per channel, l < bands (moments trilinear between nodes, zero
  // outside the grid), clamped at zero: the radiance a unit of scattering with Legendre moments chi_l
  // (per channel; chi_0 = 1 for a normalised phase function) sends along w_out.
  Rgb scattered(const Vec3& p, const Vec3& w_out, const std::array<Rgb, kShMaxBands>& chi) const;
  // The same from the pre-filtered (mip-mapped) grid, for light that reaches the camera from an area
  // of lateral standard deviation `spread` (per component) around p: level log2(spread / spacing),
  // blended between the two nearest levels (level k: 2^k spacings, a tent filter of the level below).
  Rgb scattered_filtered(const Vec3& p, const Vec3& w_out, const std::array<Rgb, kShMaxBands>& chi,
                         double spread) const;
  int bands() const { return bands_; }

  size_t memory_bytes() const {
    size_t bytes = values_.size() * sizeof(float);
    for (const auto& m : mips_) bytes += m.values.size() * sizeof(float);
    return bytes;
  }

 private:
  Bounds bounds_;  // of the node grid (the media's bounds padded by one spacing)
  std::array<int, 3> nodes_{2, 2, 2};
  Vec3 spacing_{1.0};
  int bands_ = 3, coeffs_ = 9;
  std::vector<float> values_;  // per node: channel c at [coeffs c + h]: L_lm, h = l^2 + l + m
  struct Level {
    std::array<int, 3> nodes;
    Vec3 spacing;
    std::vector<float> values;
  };
  std::vector<Level> mips_;  // levels 1, 2, ...: nodes at bounds_.lo + j spacing (may overhang bounds_)
  // The moments at p of level k (0: values_), summed into L with weight wt.
  void accumulate(int level, const Vec3& p, double wt, double* L) const;
  // sum_lm chi_l L_lm Y_lm(w_out) per channel from moments L (as values_ lays out a node), clamped at 0.
  Rgb evaluate(const double* L, const Vec3& w_out, const std::array<Rgb, kShMaxBands>& chi) const;
  void build_mips();
};

class TransmittanceGrid;

// The lights' peak-only beams (light that has not yet scattered widely) as they really travel, against
// the straight-line picture `mfs` uses for them: from the light's entry, T_wide = exp(-int (sigma_a +
// (1 - f) sigma_s)) along the straight line (the reduced shadow map), as if every peak scatter kept the
// light on its line. Peak scatters deflect it: its paths are longer (more absorption and wide
// scattering on the way, the corrected kernel's 1 / cosh loss), and near a medium's sides it spreads out
// of the medium and into its shadow. Per light and node:
//     R(x) = phi_peak(x) / (phi_0(x) T_wide(x)),
// phi_peak the fluence of the peak-only light, estimated by photons traced through the true medium:
// flights end at peak scatters only (rate sum_m f_m sigma_s,m; the new direction from P_peak), while
// absorption and wide scatters are a continuous loss exp(-int sigma_loss) on the photon's weight, so in
// a uniform medium a photon's weight depends only on its path length. Track-length deposits are each
// divided by the model phi_0 T_wide at the deposit point (phi_0: the unattenuated fluence, the
// irradiance or I / r^2), and the same photon is deposited once more undeflected (the model itself, with
// the same emission: a control variate), so R = traced / straight is 1 wherever nothing deflects the
// light. Photons enter through a stratified disc or cone (the R2 sequence). The traced deposits also
// carry the cosine to the straight direction from the light: the beam's mean cosine, which sets the
// angular spread `mfs` gives the peak-only light. `mfs` multiplies T_wide by R.
class BeamGrid {
 public:
  // reduced_maps[l]: light l's T_wide; photons: per light; resolution as ScatterGridSettings.
  BeamGrid(const SceneContext& ctx, const std::vector<const PhaseSplit*>& splits,
           const std::vector<double>& peak_fraction, const std::vector<TransmittanceGrid>& reduced_maps,
           int photons, int resolution, uint64_t seed);
  // R for light `light` at p (trilinear between nodes) and the peak-only light's mean cosine to the
  // straight direction from the light; false (nothing written) outside the grid and for other lights.
  bool lookup(size_t light, const Vec3& p, Rgb* factor, Rgb* mean_cosine) const;
  size_t memory_bytes() const;

 private:
  Bounds bounds_;
  std::array<int, 3> nodes_{2, 2, 2};
  Vec3 spacing_{1.0};
  std::vector<std::vector<float>> values_;  // per light and node: traced, traced x cosine, straight (rgb)
};

}  // namespace nimbus
