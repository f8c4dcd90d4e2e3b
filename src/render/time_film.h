// A transient render's film (film.time_bins [t0, t1, N]; docs/transient.md): per pixel the sums of the
// camera samples' timed contributions (CameraSample::timed) in N equal bins of path length over
// [t0, t1), with an underflow bin (s < t0) and an overflow bin (s >= t1, or no finite length) so that
// the bins sum to the steady image. The pixel means divide by the main film's sample counts, the
// steady image's own divisor. Pixels are independent: threads rendering disjoint tiles add without
// locks, each pixel's samples in order, so the bins are bit-identical for any thread count.
#pragma once

#include <string>
#include <vector>

#include "integrators/integrator.h"
#include "nimbus/image.h"
#include "nimbus/scene.h"
#include "render/film.h"

namespace nimbus {

class TimeFilm {
 public:
  // Throws nimbus::Error naming film.time_bins for bins a width x height image cannot hold.
  TimeFilm(int width, int height, const TimeBins& bins, bool transparent);

  // The bin of path length s: 0 underflow, 1..N the bins, N + 1 overflow.
  int bin(double s) const;
  // One camera sample's parts at pixel (x, y) (a transparent film leaves the background out).
  void add(int x, int y, const std::vector<TimedContribution>& parts);

  // The pixel means as EXR layers time_under, time0000 .. time{N-1}, time_over (R, G, B each; bin k
  // covers [t0 + k dt, t0 + (k + 1) dt)), over the main film's sample counts.
  std::vector<ImageChannel> resolve(const Film& film) const;
  // The layer name of bin b (0 .. N + 1).
  std::string layer_name(int b) const;
  // Header attributes: nimbus/time_bins "t0,t1,N", nimbus/time_bin_width, nimbus/time_layers.
  ImageMetadata metadata() const;

 private:
  int width_ = 0, height_ = 0, slots_ = 0;  // slots_ = N + 2
  TimeBins bins_;
  double inv_dt_ = 0.0;
  bool transparent_ = false;
  std::vector<double> sum_;  // (pixel, slot, channel)
};

}  // namespace nimbus
