// Adaptive sampling (render --noise): after each pass, a set of probe samples that never enter the image
// gives each pixel's variance and cost, from them the binned relative RMSE the image would show against a
// noise-free reference (the metric of nimbus compare --bin K --min-ref 0.05), and how many samples each
// pixel should have for that error to reach the target. docs/cli.md and docs/validation/render.md explain it.
#pragma once

#include <cstdint>
#include <vector>

#include "render/film.h"

namespace nimbus {

struct AdaptiveSettings {
  double noise = 0.0;           // target binned relative RMSE (0.02 = 2 %)
  int bin = 4;                  // k x k bins, as nimbus compare --bin
  double min_reference = 0.05;  // bins darker than this fraction of the mean are left out, as --min-ref
  int base_spp = 8;             // every pixel takes at least this many samples before its variance is trusted
  int max_spp = 0;              // no pixel takes more
  // The probe (samples that decide, never in the image): one probe sample for every probe_ratio image
  // samples of a pixel, and at least probe_min; a pixel's count is planned from the probe variances of
  // the (2 r + 1)^2 - 1 pixels around it (r = probe_radius), plus `shrink` times the image's mean one.
  // (Measured on the r = 2 side-lit sphere, docs/validation/render.md: the error reached for the time
  // spent was best with ratio 4 and at least 8, as many as the image's first passes take.)
  int probe_ratio = 4;
  int probe_min = 8;
  int probe_radius = 2;
  double shrink = 0.25;
};

struct AdaptivePlan {
  double estimated_error = 0.0;  // of the film as it is
  std::vector<uint32_t> target;  // samples each pixel should have after the next pass (>= its count)
  std::vector<uint32_t> probe;   // probe samples each pixel should have after it (>= its probe count)
  int64_t new_samples = 0;       // the next pass's pixel samples (0: nothing more to do)
  int64_t new_probes = 0;        // and its probe samples
};

// The film layer adaptive sampling adds: per pixel, the sums over its probe samples (samples drawn from
// random numbers of their own, which the image never takes) of 1 (their count), their luminance, its
// square and their cost (the random numbers each drew: Rng::draws_since, a count of the path's events
// that is the same on any machine and thread count).
inline constexpr const char* kAdaptiveLayer = "probe";
inline constexpr int kAdaptiveChannels = 4;
// The layer of earlier nimbus versions (sums over the image's own samples), which cannot be continued.
inline constexpr const char* kAdaptiveLayerV1 = "adaptive";
// Its grid (render/film.h): squared luminances span more than colours do, so a coarser grid than the
// colours' 2^-64 holds them from 3.6e-15 (a luminance of 6e-8) up to 2^78 (a luminance of 5.5e11) per
// sample; a sample beyond is saturated, which only lowers its pixel's variance estimate.
inline constexpr int kAdaptiveFractionBits = 48;
// Draws a sample costs besides its own (camera ray, film): keeps a pixel of draw-free samples finite.
inline constexpr double kSampleOverheadDraws = 8.0;
// Probe sample s of a pixel is sample kProbeIndexBase + s of Rng::for_sample: a stream no image sample
// (index below kMaxSpp) draws from.
inline constexpr uint64_t kProbeIndexBase = uint64_t(1) << 40;

// The probe's values of one sample, as the adaptive layer sums them.
inline void probe_values(double luminance, double draws, double out[kAdaptiveChannels]) {
  out[0] = 1.0;
  out[1] = luminance;
  out[2] = luminance * luminance;
  out[3] = draws;
}

// A pixel's probe samples so far.
inline uint32_t probe_count(const Film& film, int layer, int x, int y) {
  return uint32_t(film.sum(layer, x, y, 0) + 0.5);
}

// The next pass: pixels move towards the allocation that minimises the binned error for the cost spent
// (samples in proportion to the pixel's standard deviation over the square root of its cost per sample,
// pooled over its 3 x 3 neighbours), each at most doubling its count. Nothing more is planned once the
// estimated error is at or below the target. Every number it uses (variances, costs, means, the bins
// left out) comes from the probe samples, none from the image's: the counts, and so the stop, are
// independent of the samples that make the image, and each pixel's mean is unbiased whatever the
// samples decide (docs/cli.md). The image's sample counts enter as counts only.
AdaptivePlan plan_adaptive_pass(const Film& film, int layer, const AdaptiveSettings& settings);

}  // namespace nimbus
