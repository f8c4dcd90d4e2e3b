// Adaptive sampling (render --noise): after each pass, the film's per-pixel sums of the luminance and of
// its square estimate each pixel's variance, from them the binned relative RMSE the image would show
// against a noise-free reference (the metric of nimbus compare --bin K --min-ref 0.05), and how many
// samples each pixel should have for that error to reach the target. docs/rendering.md explains it.
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
};

struct AdaptivePlan {
  double estimated_error = 0.0;  // of the film as it is
  std::vector<uint32_t> target;  // samples each pixel should have after the next pass (>= its count)
  int64_t new_samples = 0;       // the next pass's pixel samples (0: nothing more to do)
};

// The film layer adaptive sampling adds: per pixel, the sums of each sample's squared luminance and of
// its cost (the random numbers it drew: Rng::draws_since, a count of the path's events that is the
// same on any machine and thread count).
inline constexpr const char* kAdaptiveLayer = "adaptive";
inline constexpr int kAdaptiveChannels = 2;
// Its grid (render/film.h): squared luminances span more than colours do, so a coarser grid than the
// colours' 2^-64 holds them from 3.6e-15 (a luminance of 6e-8) up to 2^78 (a luminance of 5.5e11) per
// sample; a sample beyond is saturated, which only lowers its pixel's variance estimate.
inline constexpr int kAdaptiveFractionBits = 48;
// Draws a sample costs besides its own (camera ray, film): keeps a pixel of draw-free samples finite.
inline constexpr double kSampleOverheadDraws = 8.0;

// The next pass: pixels move towards the allocation that minimises the binned error for the cost spent
// (samples in proportion to the pixel's standard deviation over the square root of its cost per sample,
// both taken from its 3 x 3 neighbours, not from its own samples: a count that its own samples decide
// biases its mean, dark where rare bright paths make the light), each at most doubling its count.
// Nothing more is planned once the estimated error is at or below the target.
AdaptivePlan plan_adaptive_pass(const Film& film, int layer, const AdaptiveSettings& settings);

}  // namespace nimbus
