#include "render/deep.h"

#include <algorithm>
#include <cmath>

namespace nimbus {

namespace {

struct Bin {
  double lo = 0.0, hi = 0.0;  // the depths the segments in it cover
  Rgb C{0.0};
  double A = 0.0;
  bool used = false;
  void add(double t0, double t1, const Rgb& c, double a) {
    lo = used ? std::min(lo, t0) : t0;
    hi = used ? std::max(hi, t1) : t1;
    C += c;
    A += a;
    used = true;
  }
};

// Every segment spread over the equal bins of [tmin, tmax] it covers, in proportion to length.
std::vector<Bin> bin_segments(const std::vector<DeepSegment>& segments, double weight, int n) {
  double tmin = segments.front().t0, tmax = segments.front().t1;
  for (const DeepSegment& s : segments) tmin = std::min(tmin, s.t0), tmax = std::max(tmax, s.t1);
  std::vector<Bin> bins(static_cast<size_t>(n));
  const double width = (tmax - tmin) / n;
  auto bin_of = [&](double t) { return width > 0.0 ? std::clamp(int((t - tmin) / width), 0, n - 1) : 0; };
  for (const DeepSegment& s : segments) {
    const int b0 = bin_of(s.t0), b1 = bin_of(s.t1);
    const double length = s.t1 - s.t0;
    for (int b = b0; b <= b1; ++b) {
      const double lo = b == b0 ? s.t0 : tmin + b * width, hi = b == b1 ? s.t1 : tmin + (b + 1) * width;
      const double share = b0 == b1 || length <= 0.0 ? 1.0 : std::max(0.0, hi - lo) / length;
      if (share > 0.0) bins[size_t(b)].add(lo, hi, s.L * (weight * share), s.alpha * weight * share);
    }
  }
  return bins;
}

}  // namespace

void merge_deep_segments(const std::vector<DeepSegment>& segments, double weight, int max_samples,
                         std::vector<DeepSample>* out) {
  out->clear();
  if (segments.empty() || max_samples < 1) return;
  std::vector<Bin> bins = bin_segments(segments, weight, 4 * max_samples);
  std::erase_if(bins, [](const Bin& b) {
    return !b.used || (b.A == 0.0 && max_component(b.C) == 0.0 && min_component(b.C) == 0.0);
  });
  // Groups of about equal alpha: bin k joins group floor(N (A_before + A_k / 2) / A_total).
  double total = 0.0;
  for (const Bin& b : bins) total += std::abs(b.A);
  std::vector<Bin> groups;
  double before = 0.0;
  int current = -1;
  for (size_t k = 0; k < bins.size(); ++k) {
    const double a = std::abs(bins[k].A);
    const double u = total > 0.0 ? (before + 0.5 * a) / total : (k + 0.5) / double(bins.size());
    const int g = std::min(max_samples - 1, int(u * max_samples));
    if (g != current || groups.empty()) groups.push_back(Bin{}), current = g;
    groups.back().add(bins[k].lo, bins[k].hi, bins[k].C, bins[k].A);
    before += a;
  }
  // Absolute shares to the deep samples' own colour and alpha, front to back.
  double front = 0.0;  // alpha of the samples in front
  for (const Bin& g : groups) {
    const double open = 1.0 - front;
    if (open < 1e-9) break;
    out->push_back({float(g.lo), float(g.hi), float(g.C[0] / open), float(g.C[1] / open),
                    float(g.C[2] / open), float(g.A / open)});
    front += g.A;
  }
}

}  // namespace nimbus
