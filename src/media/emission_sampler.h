// Points of the media drawn in proportion to their emitted power, for photons that start inside the
// volume (the emission of `mfs`'s scatter grid: a fire lights its own smoke).
//
// A regular grid of cells over the media's bounds holds each cell's estimated emission (the largest
// channel of j at 3 x 3 x 3 points, plus a small floor where media/emission.h says the cell may emit, so
// that no emitting point has zero density); a cell is drawn from their cumulative sum, then a uniform
// point in it. The density is exact (pdf below), so 4 pi j(x) / pdf(x) is an unbiased estimate of the
// emitted power, however rough the cell estimates.
#pragma once

#include <vector>

#include "core/math.h"
#include "media/media.h"

namespace nimbus {

class EmissionSampler {
 public:
  // resolution: cells along the longest axis of the media's bounds.
  EmissionSampler() = default;  // inactive
  explicit EmissionSampler(const SceneMedia& media, int resolution = 32);
  // False when no medium emits (nothing to draw).
  bool active() const { return total_ > 0.0; }
  // A point from three uniform numbers in [0, 1) (u0 picks the cell, u1, u2 and u3's fraction place the
  // point); *pdf is its density per unit volume.
  Vec3 sample(double u0, double u1, double u2, double u3, double* pdf) const;

 private:
  Bounds bounds_;
  std::array<int, 3> res_{1, 1, 1};
  Vec3 cell_{1.0};
  std::vector<double> cdf_;  // cumulative cell weights
  double total_ = 0.0;
};

}  // namespace nimbus
