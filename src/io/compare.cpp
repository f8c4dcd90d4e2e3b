// Image comparison metrics and the error heat map (nimbus/compare.h).
#include "nimbus/compare.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "nimbus/error.h"

namespace nimbus {

namespace {

double lum(const float* p) { return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]; }

struct Binned {
  int nx = 0, ny = 0;
  std::vector<double> a, b;  // luminance per bin
};

Binned bin_luminance(const Image& a, const Image& b, int k) {
  Binned r;
  r.nx = (a.width + k - 1) / k;
  r.ny = (a.height + k - 1) / k;
  r.a.assign(size_t(r.nx) * r.ny, 0.0);
  r.b.assign(size_t(r.nx) * r.ny, 0.0);
  std::vector<int> count(r.a.size(), 0);
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x) {
      const size_t i = size_t(y / k) * r.nx + x / k;
      r.a[i] += lum(a.pixel(x, y));
      r.b[i] += lum(b.pixel(x, y));
      ++count[i];
    }
  for (size_t i = 0; i < r.a.size(); ++i) {
    r.a[i] /= count[i];
    r.b[i] /= count[i];
  }
  return r;
}

void check(const Image& a, const Image& b, const CompareOptions& o) {
  if (a.width != b.width || a.height != b.height)
    throw Error(
        fmt::format("images differ in size: {}x{} against {}x{}", a.width, a.height, b.width, b.height));
  if (o.bin < 1) throw Error("bin size must be >= 1");
  if (!(o.min_reference >= 0.0)) throw Error("min_reference must be >= 0");
}

}  // namespace

CompareResult compare_images(const Image& a, const Image& b, const CompareOptions& o) {
  check(a, b, o);
  CompareResult r;
  const size_t n = size_t(a.width) * a.height;
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) {
      r.mean_a[c] += a.rgb[i * 3 + c];
      r.mean_b[c] += b.rgb[i * 3 + c];
    }
  for (int c = 0; c < 3; ++c) {
    r.mean_a[c] /= double(n);
    r.mean_b[c] /= double(n);
  }
  r.mean_lum_a = 0.2126 * r.mean_a[0] + 0.7152 * r.mean_a[1] + 0.0722 * r.mean_a[2];
  r.mean_lum_b = 0.2126 * r.mean_b[0] + 0.7152 * r.mean_b[1] + 0.0722 * r.mean_b[2];
  r.mean_rel_error = r.mean_lum_b > 0 ? (r.mean_lum_a - r.mean_lum_b) / r.mean_lum_b : 0.0;

  const Binned bins = bin_luminance(a, b, o.bin);
  r.bins_total = int(bins.a.size());
  double mean_ref_all = 0.0;
  for (double v : bins.b) mean_ref_all += v;
  mean_ref_all /= double(bins.b.size());
  double sq = 0.0, ref = 0.0, abs_rel = 0.0;
  for (size_t i = 0; i < bins.a.size(); ++i) {
    if (!(bins.b[i] > 0.0) || bins.b[i] < o.min_reference * mean_ref_all) continue;
    const double d = bins.a[i] - bins.b[i];
    sq += d * d;
    ref += bins.b[i];
    abs_rel += std::abs(d) / bins.b[i];
    r.max_abs_rel_error = std::max(r.max_abs_rel_error, std::abs(d) / bins.b[i]);
    ++r.bins_used;
  }
  if (r.bins_used > 0) {
    r.rel_rmse = std::sqrt(sq / r.bins_used) / (ref / r.bins_used);
    r.mean_abs_rel_error = abs_rel / r.bins_used;
  }
  return r;
}

Image error_heatmap(const Image& a, const Image& b, const CompareOptions& o, double max_rel) {
  check(a, b, o);
  const Binned bins = bin_luminance(a, b, o.bin);
  double mean_ref_all = 0.0;
  for (double v : bins.b) mean_ref_all += v;
  mean_ref_all /= double(bins.b.size());
  Image out(a.width, a.height);
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x) {
      const size_t i = size_t(y / o.bin) * bins.nx + x / o.bin;
      float* p = out.pixel(x, y);
      if (!(bins.b[i] > 0.0) || bins.b[i] < o.min_reference * mean_ref_all) {
        p[0] = p[1] = p[2] = 0.2f;
        continue;
      }
      heatmap_colour((bins.a[i] - bins.b[i]) / bins.b[i] / max_rel, p);
    }
  return out;
}

void heatmap_colour(double e, float rgb[3]) {
  e = std::isnan(e) ? 0.0 : std::clamp(e, -1.0, 1.0);
  rgb[0] = float(e < 0 ? 1.0 + e : 1.0);
  rgb[1] = float(1.0 - std::abs(e));
  rgb[2] = float(e > 0 ? 1.0 - e : 1.0);
}

}  // namespace nimbus
