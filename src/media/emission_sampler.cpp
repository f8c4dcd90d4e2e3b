// The emission sampler (media/emission_sampler.h).
#include "media/emission_sampler.h"

#include <tbb/parallel_for.h>

#include <algorithm>

namespace nimbus {

EmissionSampler::EmissionSampler(const SceneMedia& media, int resolution) {
  if (!media.emits() || media.bounds().empty()) return;
  bounds_ = media.bounds();
  const Vec3 e = bounds_.hi - bounds_.lo;
  const double longest = std::max({e.x, e.y, e.z});
  for (int a = 0; a < 3; ++a) {
    res_[a] = std::clamp(int(std::ceil(e[a] / longest * resolution)), 1, resolution);
    cell_[a] = e[a] / res_[a];
  }
  const size_t n = size_t(res_[0]) * res_[1] * res_[2];
  std::vector<double> w(n, 0.0);
  std::vector<char> may(n, 0);
  tbb::parallel_for(0, res_[2], [&](int z) {
    for (int y = 0; y < res_[1]; ++y)
      for (int x = 0; x < res_[0]; ++x) {
        const size_t c = (size_t(z) * res_[1] + y) * res_[0] + x;
        Bounds box;
        box.lo = bounds_.lo + Vec3(x, y, z) * cell_;
        box.hi = box.lo + cell_;
        for (int i = 0; i < media.count(); ++i) may[c] = may[c] || media.may_emit(i, box);
        if (!may[c]) continue;
        double sum = 0.0;
        for (int k = 0; k < 27; ++k) {
          const Vec3 f((k % 3 + 0.5) / 3.0, (k / 3 % 3 + 0.5) / 3.0, (k / 9 + 0.5) / 3.0);
          sum += max_component(media.emission(box.lo + f * cell_));
        }
        w[c] = sum / 27.0;
      }
  });
  // The floor: 1e-3 of the mean weight of the cells that may emit.
  double sum = 0.0;
  size_t cells = 0;
  for (size_t c = 0; c < n; ++c)
    if (may[c]) sum += w[c], ++cells;
  if (cells == 0) return;
  const double floor = sum > 0.0 ? 1e-3 * sum / double(cells) : 1.0;
  cdf_.resize(n);
  double acc = 0.0;
  for (size_t c = 0; c < n; ++c) {
    if (may[c]) acc += w[c] + floor;
    cdf_[c] = acc;
  }
  total_ = acc;
}

Vec3 EmissionSampler::sample(double u0, double u1, double u2, double u3, double* pdf) const {
  const double target = u0 * total_;
  size_t c = size_t(std::upper_bound(cdf_.begin(), cdf_.end(), target) - cdf_.begin());
  c = std::min(c, cdf_.size() - 1);
  while (c > 0 && cdf_[c] == cdf_[c - 1]) --c;  // never a zero-weight cell (u0 on a boundary)
  const double wc = cdf_[c] - (c > 0 ? cdf_[c - 1] : 0.0);
  *pdf = wc / (total_ * cell_.x * cell_.y * cell_.z);
  const int x = int(c % res_[0]), y = int(c / res_[0] % res_[1]), z = int(c / (size_t(res_[0]) * res_[1]));
  return bounds_.lo + Vec3(x + u1, y + u2, z + u3) * cell_;
}

}  // namespace nimbus
