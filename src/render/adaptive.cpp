#include "render/adaptive.h"

#include <algorithm>
#include <cmath>

#include "core/math.h"

namespace nimbus {

namespace {

// Per pixel, from its probe samples: the mean luminance, the unbiased variance of one sample's luminance
// (0 below 2 samples) and the mean cost of a sample.
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
      const double n = probe_count(film, layer, x, y);
      if (n < 1) continue;
      const size_t i = size_t(y) * W + x;
      const double sum = film.sum(layer, x, y, 1), sum2 = film.sum(layer, x, y, 2);
      p.mean[i] = sum / n;
      p.cost[i] += film.sum(layer, x, y, 3) / n;
      if (n >= 2) p.var[i] = std::max(0.0, (sum2 - sum * sum / n) / (n - 1));
    }
  return p;
}

// The mean over the pixel's (2 r + 1)^2 neighbours (those inside the image), the pixel itself included
// or not (not: when none is left, its own value).
std::vector<double> pooled(const std::vector<double>& var, int W, int H, int r, bool self) {
  std::vector<double> out(var.size(), 0.0);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      double s = 0.0;
      int n = 0;
      for (int dy = -r; dy <= r; ++dy)
        for (int dx = -r; dx <= r; ++dx) {
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
  const int bx = (W + k - 1) / k, by = (H + k - 1) / k;
  // Per bin: mean luminance, the variance of that mean, its pixel count.
  std::vector<double> bin_mean(size_t(bx) * by, 0.0), bin_var(bin_mean.size(), 0.0), bin_m(bin_mean.size());
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const size_t i = size_t(y) * W + x, b = size_t(y / k) * bx + x / k;
      const double n = std::max<double>(1.0, film.samples(x, y));
      bin_mean[b] += px.mean[i];
      bin_var[b] += px.var[i] / n;
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
  double ysum = 0.0, vsum = 0.0;
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
  plan.probe.resize(plan.target.size());
  const double ybar = used_bins > 0 ? ysum / used_bins : 0.0;
  // The estimate takes each pixel's own probe variance, its count comes from its neighbours' (below):
  // the two are independent, so that for the counts planned the estimate's expectation is the error's
  // (a pixel whose probe missed its bright paths would otherwise both take few samples and count as
  // quiet, and the render would stop early).
  plan.estimated_error = ybar > 0.0 ? std::sqrt(vsum / used_bins) / ybar : 0.0;
  // Relative counts w_i = sqrt(v_i / c_i) / m_b, with v_i and c_i pooled over the pixel's neighbours
  // (not itself) and v_i shrunk towards the mean variance of the image's pixels (the probe has few
  // samples per pixel, and a pixel whose neighbours' probes missed a rare bright path would otherwise
  // take hardly any samples): they minimise sum_b sum_i v_i / (m_b^2 n_i) for the cost sum_i c_i n_i.
  const int r = std::max(1, settings.probe_radius);
  const std::vector<double> v_nb = pooled(px.var, W, H, r, false), c_nb = pooled(px.cost, W, H, r, false);
  double v_mean = 0.0, used_px = 0.0;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x)
      if (used[size_t(y / k) * bx + x / k]) v_mean += px.var[size_t(y) * W + x], used_px += 1.0;
  v_mean = used_px > 0.0 ? v_mean / used_px : 0.0;
  std::vector<double> w(plan.target.size(), 0.0);
  double lambda_sum =
      0.0;  // sum_i v_i / (m_b^2 w_i): the squared error of counts n_i = w_i, times bins ybar^2
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const size_t i = size_t(y) * W + x, b = size_t(y / k) * bx + x / k;
      if (!used[b]) continue;
      w[i] = std::sqrt((v_nb[i] + settings.shrink * v_mean) / c_nb[i]) / bin_m[b];
      if (w[i] > 0.0) lambda_sum += px.var[i] / (bin_m[b] * bin_m[b] * w[i]);
    }
  // Counts n_i = lambda w_i give the target error e for lambda = lambda_sum / (bins e^2 ybar^2).
  // Every number here is the probe's, none the image's: docs/cli.md has why the image's samples must
  // decide nothing (its samples deciding the stop darkened the r = 2 side-lit sphere by 7 % at 0.2).
  const double goal = settings.noise * ybar;
  const double lambda = goal > 0.0 ? lambda_sum / (used_bins * goal * goal) : 0.0;
  const bool done = plan.estimated_error <= settings.noise;
  const uint32_t cap = uint32_t(std::max(settings.max_spp, 1));
  const uint32_t base = std::min(cap, uint32_t(std::max(settings.base_spp, 1)));
  const uint32_t ratio = uint32_t(std::max(settings.probe_ratio, 1)),
                 pmin = uint32_t(std::max(settings.probe_min, 0));
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const size_t i = size_t(y) * W + x;
      const uint32_t n = film.samples(x, y);
      double want = base;
      if (!done && w[i] > 0.0) want = std::max(want, std::ceil(lambda * w[i]));
      const double grown = std::min({want, 2.0 * std::max<double>(n, 1.0), double(cap)});
      plan.target[i] = std::max(n, uint32_t(grown));
      plan.new_samples += plan.target[i] - n;
      const uint32_t pn = probe_count(film, layer, x, y);
      plan.probe[i] = std::max({pn, (plan.target[i] + ratio - 1) / ratio, std::min(plan.target[i], pmin)});
      plan.new_probes += plan.probe[i] - pn;
    }
  return plan;
}

}  // namespace nimbus
