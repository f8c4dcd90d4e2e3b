// Monte Carlo estimates of an integrator's radiance along one ray, channel by channel.
#pragma once

#include <cstdint>

#include "core/rng.h"
#include "integrators/integrator.h"
#include "support/stats.h"

namespace nimbus::test {

struct ChannelStats {
  MeanAccumulator c[3];
};

// The mean and standard error of Li over n samples, sample i seeded (seed, i).
inline ChannelStats estimate_li(const Integrator& it, const Vec3& o, const Vec3& d, int n,
                                uint64_t seed = 1) {
  ChannelStats s;
  for (int i = 0; i < n; ++i) {
    Rng rng(seed, uint64_t(i));
    const Rgb L = it.Li({o, d}, rng);
    for (int k = 0; k < 3; ++k) s.c[k].add(L[k]);
  }
  return s;
}

}  // namespace nimbus::test
