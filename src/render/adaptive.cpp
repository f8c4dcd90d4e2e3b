#include "render/adaptive.h"

#include <algorithm>
#include <cmath>

#include "core/math.h"

namespace nimbus {

namespace {

// Per pixel: the mean luminance, the unbiased variance of one sample's luminance (0 below 2 samples) and
// the mean cost of a sample.
struct PixelStats {
  std::vector<double> mean, var, cost;
};

PixelStats pixel_stats(const Film& film, int layer) {
  const int W = film.width(), H = film.height();
  const size_t n_px = size_t(W) * size_t(H);
  PixelStats p{std::vector<double>(n_px, 0.0), std::vector<double>(n_px, 0.0),
               std::vector<double>(n_px, kSampleOverheadDraws)};
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const double n = film.samples(x, y);
      if (n < 1) continue;
      const size_t i = size_t(y) * W + x;
      const Rgb rgb(film.sum(0, x, y, 0), film.sum(0, x, y, 1), film.sum(0, x, y, 2));
      const double sum = luminance(rgb), sum2 = film.sum(layer, x, y, 0);
      p.mean[i] = sum / n;
      p.cost[i] += film.sum(layer, x, y, 1) / n;
      if (n >= 2) p.var[i] = std::max(0.0, (sum2 - sum * sum / n) / (n - 1));
    }
  return p;
}

// The mean over the pixel's 3 x 3 neighbours (those inside the image), the pixel itself included or
// not (not: when none is left, its own value).
std::vector<double> pooled(const std::vector<double>& var, int W, int H, bool self) {
  std::vector<double> out(var.size(), 0.0);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      double s = 0.0;
      int n = 0;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int u = x + dx, v = y + dy;
          if (u < 0 || v < 0 || u >= W || v >= H || (!self && dx == 0 && dy == 0)) continue;
          s += var[size_t(v) * W + u];
          ++n;
        }
      out[size_t(y) * W + x] = n > 0 ? s / n : var[size_t(y) * W + x];
    }
  return out;
}

}  // namespace

AdaptivePlan plan_adaptive_pass(const Film& film, int layer, const AdaptiveSettings& settings) {
  const int W = film.width(), H = film.height(), k = std::max(1, settings.bin);
  const PixelStats px = pixel_stats(film, layer);
  const std::vector<double> v = pooled(px.var, W, H, true), c = pooled(px.cost, W, H, true);
  const int bx = (W + k - 1) / k, by = (H + k - 1) / k;
  // Per bin: mean luminance, the variance of that mean, its pixel count and sum of sqrt(v) / m.
  std::vector<double> bin_mean(size_t(bx) * by, 0.0), bin_var(bin_mean.size(), 0.0), bin_m(bin_mean.size());
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const size_t i = size_t(y) * W + x, b = size_t(y / k) * bx + x / k;
      const double n = std::max<double>(1.0, film.samples(x, y));
      bin_mean[b] += px.mean[i];
      bin_var[b] += v[i] / n;
      bin_m[b] += 1.0;
    }
  double all = 0.0;
  for (size_t b = 0; b < bin_mean.size(); ++b) {
    bin_mean[b] /= bin_m[b];
    bin_var[b] /= bin_m[b] * bin_m[b];
    all += bin_mean[b];
  }
  all /= double(bin_mean.size());
  std::vector<char> used(bin_mean.size(), 0);
  double ysum = 0.0, vsum = 0.0, root_sum = 0.0;
  int used_bins = 0;
  for (size_t b = 0; b < bin_mean.size(); ++b) {
    used[b] = bin_mean[b] > 0.0 && bin_mean[b] >= settings.min_reference * all;
    if (!used[b]) continue;
    ++used_bins;
    ysum += bin_mean[b];
    vsum += bin_var[b];
  }
  AdaptivePlan plan;
  plan.target.resize(size_t(W) * H);
  const double ybar = used_bins > 0 ? ysum / used_bins : 0.0;
  plan.estimated_error = ybar > 0.0 ? std::sqrt(vsum / used_bins) / ybar : 0.0;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const size_t b = size_t(y / k) * bx + x / k;
      const size_t i = size_t(y) * W + x;
      if (used[b]) root_sum += std::sqrt(v[i] * c[i]) / bin_m[b];
    }
  // Samples n_i = lambda sqrt(v_i / c_i) / m_b minimise sum_b sum_i v_i / (m_b^2 n_i) for their cost
  // sum_i c_i n_i, and give the target error for lambda = sum_i sqrt(v_i c_i) / m_b / (bins e^2 ybar^2).
  // A pixel's own count is planned from its neighbours' variance and cost and its bin's other pixels:
  // were its own samples to decide, a pixel whose first samples missed a rare bright path would look
  // converged and stop dark while one that caught it would take more, and the image would be biased
  // dark (-4 to -17 % on the suite's spheres at --noise 0.2). Its own samples still enter the
  // image-wide sums (lambda, the stopping test), with a weight of one pixel in all of them.
  const std::vector<double> v_nb = pooled(px.var, W, H, false), c_nb = pooled(px.cost, W, H, false);
  const double goal = settings.noise * ybar, lambda = goal > 0.0 ? root_sum / (used_bins * goal * goal) : 0.0;
  const bool done = plan.estimated_error <= settings.noise;
  auto used_without = [&](size_t i, size_t b) {  // the bin's mean over its other pixels, as `used`
    const double others =
        bin_m[b] > 1.0 ? (bin_mean[b] * bin_m[b] - px.mean[i]) / (bin_m[b] - 1.0) : bin_mean[b];
    return others > 0.0 && others >= settings.min_reference * all;
  };
  const uint32_t cap = uint32_t(std::max(settings.max_spp, 1));
  const uint32_t base = std::min(cap, uint32_t(std::max(settings.base_spp, 1)));
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const size_t i = size_t(y) * W + x, b = size_t(y / k) * bx + x / k;
      const uint32_t n = film.samples(x, y);
      double want = base;
      if (!done && used_without(i, b))
        want = std::max(want, std::ceil(lambda * std::sqrt(v_nb[i] / c_nb[i]) / bin_m[b]));
      const double grown = std::min({want, 2.0 * std::max<double>(n, 1.0), double(cap)});
      plan.target[i] = std::max(n, uint32_t(grown));
      plan.new_samples += plan.target[i] - n;
    }
  return plan;
}

}  // namespace nimbus
