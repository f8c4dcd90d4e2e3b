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
// flights deposit from order 0, so `mfs` needs no environment sampling on the camera ray. An environment
// image's photons leave it by luminance (integrators/env_light.h): the grid holds its moments l <= 2.
//
// Chromatic media (coefficients that differ between channels) take one pass of photons carrying all
// three channels: photon i of a source is driven by hero channel i mod 3 (that channel's extinction for
// delta tracking, its scattering shares for the medium) and weighted per channel by the balance
// heuristic over the three channels' tracking densities (null collisions and scatters alike; the
// weights are at most 3 x the one-channel walk's albedo products; roulette on the largest channel).
// Unbiased per channel; in long walks where the channels' extinctions differ the weights all but pick
// the photons of the channel's own hero, so each channel's noise is about that of a third of the photons
// (the chromatic box: noise variance ~2.8x at 2^18 photons, for 0.6x the set-up; docs/benchmarks.md).
// channel_passes keeps the former one pass per channel (each with that channel's coefficients).
//
// Deterministic: photon i uses its own random stream; photons are split into a fixed number of
// batches (each its own grid, summed in order), so the grid does not depend on the thread count.
// The photons are traced by the shared photon tracer (integrators/photon_tracer.h); the node layout
// and its trilinear lookup are core/node_grid.h's.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "core/node_grid.h"
#include "core/sh.h"
#include "core/zeroed_floats.h"
#include "integrators/integrator.h"
#include "media/majorant.h"
#include "transport/phase_split.h"

namespace nimbus {

struct ScatterGridSettings {
  int photons = 1 << 18;  // per pass, shared among the lights (see power_share)
  // More photons where they are cheap: when > 0, a pilot of kPilotPhotons (scatter_grid.cpp) counts the
  // photons' collisions per photon C (real and null: the tracking's work), and the grid traces
  // adaptive_photons x clamp(sqrt(kDenseCollisions / C), 1/2, 4) instead of `photons`. A photon's cost grows
  // with C while on thin media the grid's noise is most of the error, so thin media buy their error with
  // more photons and very dense ones with fewer (docs/benchmarks.md, "Photons by collisions" and "Photons by
  // collisions in dense media"). `mfs`'s "auto" photons: its image size's count (auto_photons), so the two
  // factors multiply; 0 for a count given.
  int adaptive_photons = 0;
  // Run the pilot and report its collisions per photon (collisions_per_photon) for a count given too:
  // `mfs`'s "auto" beam photons read them (auto_beam_photons: thin media take more), whatever `photons` is.
  bool pilot = false;
  // Chromatic media: one photon pass per channel, each with that channel's coefficients (true), or one
  // pass of hero-channel photons carrying all three (false; scatter_grid.cpp's HeroWalk). Grey media
  // take one pass either way.
  bool channel_passes = false;
  // The lights' (and the environment's, the media's emission's) shares of the photons: power_share by
  // their power, the rest evenly. 0.8 against 0 (even) lowers the Disney cloud's photon noise variance
  // by ~12 % (its sun has 73 % of the power; docs/benchmarks.md, issue 12).
  double power_share = 0.8;
  int resolution = 0;           // nodes along the longest axis of the media's bounds; 0: "auto" (mfs)
  int max_wide_scatters = 0;    // K: flights after wide scatter 1 .. K-1 are kept; 0 = all orders
  bool exact_transport = true;  // photons in the true medium (every collision; scatters classified peak
                                // or wide by their share) or (false) in the similarity medium
  int bands = 3;                // spherical-harmonic bands used at lookup: 2 (l <= 1) or 3 (l <= 2)
  // Deposit only into the nodes that a lookup where the extinction is non-zero can read (corners of
  // cells that overlap a non-zero majorant cell); the others stay 0. For `mfs` without
  // filtered_lookups (which reads the pre-filtered levels, built from every node): the image is
  // bit-identical and the set-up ~5 % cheaper on the Disney cloud (docs/benchmarks.md, issue 12).
  bool live_nodes_only = false;
  // Build the pre-filtered levels (scattered_filtered reads them; without them it reads the grid itself).
  // `mfs` builds them only for filtered_lookups: the same images, less set-up.
  bool prefiltered = true;
  // How each deposit sample spreads over the 8 nodes around it (core/node_grid.h): trilinearly, or
  // whole to one of them drawn by its trilinear weight (the same expected grid, one write instead of 8).
  // Trilinear by default: on the Disney cloud the stochastic splat saves ~4 % of the set-up and adds
  // ~8 % to the photon noise variance (one write still takes its cache miss; docs/benchmarks.md).
  Splat splat = Splat::trilinear;
  // A flight's track-length deposit: samples at most deposit_step node spacings apart, one in each equal
  // part of the flight (clipped to the grid) at an offset drawn once per flight, so that each is unbiased
  // for its part's integral of the trilinear weights at any step. Samples at the parts' midpoints
  // (deposit_midpoints, for tests) are not, where the flights' density changes within a step (at the
  // media's sides): at 3 and 4 spacings they darkened the side-lit r = 10 sphere by 0.5 and 1.2 points.
  // 2 (against midpoints 1 spacing apart before) halves the samples of long flights for at most 1 % more
  // binned error with the same photons (docs/benchmarks.md, "Jittered deposit samples").
  double deposit_step = 2.0;
  bool deposit_midpoints = false;
  uint64_t seed = 1;
  const MajorantGrid* majorants = nullptr;  // the photons' tracking majorants (null: the scene's)
  // Filter the nodes inside the media where their difference from their neighbours is noise, by the
  // photon batches' spread (integrators/grid_denoise.h; `mfs`'s grid_denoise).
  bool denoise = false;
  // With 3 bands: a lookup also takes the light's moments l = 3 .. kShMaxBands - 1, extrapolated from a lobe
  // about its l = 1 direction d (the l-th Legendre moment along d proportional to (2l + 1) r^l, r from the
  // l = 1 and l = 2 moments along d: exact for an isotropic part plus an HG lobe), each times the chi_l the
  // lookup is given. Truncated at l = 2, the wide phase function read the light's forward lobe as if it were
  // smooth: the front-lit r = 2 sphere's second wide scatter was +2.2 % of its image too bright
  // (docs/derivations.md D12a).
  bool lobe_tail = false;
};

class ScatterGrid {
 public:
  // splits[i], peak_fraction[i]: medium i's phase split (as `mfs` uses it).
  ScatterGrid(const SceneContext& ctx, const std::vector<const PhaseSplit*>& splits,
              const std::vector<double>& peak_fraction, const ScatterGridSettings& settings);

  // sum_lm chi_l L_lm(p) Y_lm(w_out) per channel, l < bands (moments trilinear between nodes, zero
  // outside the grid), clamped at zero: the radiance a unit of scattering with Legendre moments chi_l
  // (per channel; chi_0 = 1 for a normalised phase function) sends along w_out. With the lobe tail, plus
  // chi_l times the tail's band l for bands <= l < kShMaxBands: chi must hold 0 there where none is wanted.
  Rgb scattered(const Vec3& p, const Vec3& w_out, const std::array<Rgb, kShMaxBands>& chi) const;
  // The same with Y_lm(w_out) evaluated once (ShBasis(w_out, bands())) for many points (bit for bit).
  Rgb scattered(const Vec3& p, const ShBasis& y_out, const std::array<Rgb, kShMaxBands>& chi) const;
  // The same from st, node_grid().stencil(p), found once for grids of the same layout (the beam grid's).
  Rgb scattered(const Vec3& p, const TrilinearStencil& st, const ShBasis& y_out,
                const std::array<Rgb, kShMaxBands>& chi) const;
  const NodeGrid& node_grid() const { return grid_; }
  // The same from the pre-filtered (mip-mapped) grid, for light that reaches the camera from an area
  // of lateral standard deviation `spread` (per component) around p: level log2(spread / spacing),
  // blended between the two nearest levels (level k: 2^k spacings, a tent filter of the level below).
  Rgb scattered_filtered(const Vec3& p, const Vec3& w_out, const std::array<Rgb, kShMaxBands>& chi,
                         double spread) const;
  Rgb scattered_filtered(const Vec3& p, const ShBasis& y_out, const std::array<Rgb, kShMaxBands>& chi,
                         double spread) const;
  int bands() const { return bands_; }
  // The moments chi_l a lookup reads, l < moments_read(): bands(), or kShMaxBands with the lobe tail.
  int moments_read() const { return lobe_tail_ ? kShMaxBands : bands_; }

  // Similarity transport only: wide scatters whose direction the rejection sampler could not draw (the
  // photon flew on undeflected; see sample_by_rejection). 0 in every normal case.
  uint64_t rejection_failures() const { return rejection_failures_; }
  // The photons traced per pass (settings.photons, or what adaptive_photons made of it).
  int photons() const { return photons_; }
  // The pilot's real and null collisions per photon (adaptive_photons or pilot), if it ran.
  std::optional<double> collisions_per_photon() const { return collisions_per_photon_; }

  size_t memory_bytes() const {
    size_t bytes = values_.size() * sizeof(float);
    for (const auto& m : mips_) bytes += m.values.size() * sizeof(float);
    return bytes;
  }

 private:
  NodeGrid grid_;  // the media's bounds padded by one spacing (node_grid_padded)
  int bands_ = 3, coeffs_ = 9;
  bool lobe_tail_ = false;  // ScatterGridSettings::lobe_tail, with 3 bands
  int photons_ = 0;
  std::optional<double> collisions_per_photon_;
  uint64_t rejection_failures_ = 0;
  // Channels per node: 1 where every source's photons carry one colour (tint_, max channel 1; grey
  // media lit by lights of one tint), else 3.
  int channels_ = 3;
  Rgb tint_{1.0};
  FloatArray values_;  // per node: channel c at [coeffs c + h]: L_lm, h = l^2 + l + m (c = 0 only if
                       // channels_ is 1: the moments in units of tint_)
  struct Level {
    NodeGrid grid;  // nodes at grid_.bounds.lo + j spacing (may overhang grid_.bounds)
    FloatArray values;
  };
  std::vector<Level> mips_;  // levels 1, 2, ...
  // The moments at p of level k (0: values_), summed into L with weight wt.
  void accumulate(int level, const Vec3& p, double wt, double* L) const;
  // The same from the level's stencil st at p and its values v.
  void accumulate(const TrilinearStencil& st, const float* v, double wt, double* L) const;
  // sum_lm chi_l L_lm Y_lm(w_out) per channel from moments L (as values_ lays out a node), clamped at 0.
  Rgb evaluate(const double* L, const ShBasis& y_out, const std::array<Rgb, kShMaxBands>& chi) const;
  // The photons of the constructor (settings s) into values_.
  void trace(const SceneContext& ctx, const std::vector<const PhaseSplit*>& splits,
             const std::vector<double>& peak_fraction, const ScatterGridSettings& s);
  void build_mips();
};

}  // namespace nimbus
