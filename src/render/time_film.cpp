#include "render/time_film.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "nimbus/error.h"

namespace nimbus {

TimeFilm::TimeFilm(int width, int height, const TimeBins& bins, bool transparent)
    : width_(width), height_(height), slots_(bins.count + 2), bins_(bins), transparent_(transparent) {
  if (!(bins.t0 >= 0.0 && bins.t1 > bins.t0 && std::isfinite(bins.t1)) || bins.count < 1 ||
      bins.count > kMaxTimeBins)
    throw Error(
        fmt::format("film.time_bins [{}, {}, {}]: must be [t0, t1, N] with 0 <= t0 < t1 and 1 <= N <= {}",
                    bins.t0, bins.t1, bins.count, kMaxTimeBins));
  const double values = double(width) * height * slots_ * 3;
  if (values > kMaxTimeBinValues)
    throw Error(
        fmt::format("film.time_bins: {} bins of a {}x{} image need {:.1f} GiB of sums (at most {:.0f})",
                    bins.count, width, height, values * 8 / (1 << 30), kMaxTimeBinValues * 8 / (1 << 30)));
  inv_dt_ = bins.count / (bins.t1 - bins.t0);
  sum_.assign(size_t(values), 0.0);
}

int TimeFilm::bin(double s) const {
  if (s < bins_.t0) return 0;
  if (!(s < bins_.t1)) return slots_ - 1;  // past t1, or not a finite length
  return 1 + std::min(bins_.count - 1, int((s - bins_.t0) * inv_dt_));
}

void TimeFilm::add(int x, int y, const std::vector<TimedContribution>& parts) {
  double* pixel = &sum_[(size_t(y) * size_t(width_) + size_t(x)) * size_t(slots_) * 3];
  for (const TimedContribution& p : parts) {
    if (transparent_ && p.background) continue;
    double* s = pixel + 3 * bin(p.s);
    s[0] += p.L[0];
    s[1] += p.L[1];
    s[2] += p.L[2];
  }
}

namespace {
// Bin numbers are zero-padded to 4 digits, or to as many as the last bin needs (over 10000 bins), so that
// the layers sort in time order by name.
int time_layer_digits(int count) { return std::max(4, int(std::to_string(std::max(0, count - 1)).size())); }
}  // namespace

std::string TimeFilm::layer_name(int b) const {
  if (b == 0) return "time_under";
  if (b == slots_ - 1) return "time_over";
  return fmt::format("time{:0{}d}", b - 1, time_layer_digits(bins_.count));
}

std::vector<ImageChannel> TimeFilm::resolve(const Film& film) const {
  const size_t n = size_t(width_) * size_t(height_);
  std::vector<ImageChannel> out;
  for (int b = 0; b < slots_; ++b)
    for (const char* c : {"R", "G", "B"})
      out.push_back({layer_name(b) + "." + c, std::vector<float>(n, 0.0f)});
  for (int y = 0; y < height_; ++y)
    for (int x = 0; x < width_; ++x) {
      const size_t i = size_t(y) * size_t(width_) + size_t(x);
      const uint32_t count = film.samples(x, y);
      if (count == 0) continue;
      for (int k = 0; k < slots_ * 3; ++k)
        out[size_t(k)].data[i] = float(sum_[i * size_t(slots_) * 3 + size_t(k)] / count);
    }
  return out;
}

ImageMetadata TimeFilm::metadata() const {
  return {{"nimbus/time_bins", fmt::format("{},{},{}", bins_.t0, bins_.t1, bins_.count)},
          {"nimbus/time_bin_width", fmt::format("{}", (bins_.t1 - bins_.t0) / bins_.count)},
          {"nimbus/time_layers", fmt::format("time_under (s < {}), {} .. {}, time_over (s >= {})", bins_.t0,
                                             layer_name(1), layer_name(slots_ - 2), bins_.t1)}};
}

}  // namespace nimbus
