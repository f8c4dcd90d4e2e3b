// Heavier lidar checks (src/transport/lidar.h): the Monte Carlo against the single-scatter equation with a
// disk receiver through its overlap region and a refractive index, and the fused model against the
// Monte Carlo where docs/validation/lidar.md says it holds (first mean free path, sharp peak) and where
// it says it is low (deeper).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "transport/lidar.h"

namespace nimbus {
namespace {

TEST(LidarSlow, DiskReceiverOverlapAndIndexMatchTheSingleScatterEquation) {
  // r = 0.05, fov = 20 mrad: the disk sees the whole axis beyond R_o = 2.5, a growing part before.
  LidarSettings s;
  s.sigma_s = 0.05;
  s.sigma_a = 0.01;
  s.phase = HgPhase{0.5};  // flat near pi: p(pi - small angle) = p(pi)
  s.thickness = 3.0;
  s.distance = 1.0;
  s.r_rx = 0.05;
  s.fov = 0.02;
  s.n = 1.33;
  for (int i = 0; i <= 12; ++i) s.time_edges.push_back(2.0 * s.n * (1.0 + 0.25 * i));  // R = 1 .. 4
  s.photons = 4000000;
  const LidarMcResult mc = run_lidar_mc(s);
  const std::vector<double> ss = lidar_single_scatter(s);
  for (size_t i = 0; i < ss.size(); ++i) {
    const Estimate& e = mc.received.bins[i];
    EXPECT_LT(e.err, 0.03 * ss[i]) << i;
    // 5 sigma, plus 1 % for the small-angle geometry of the equation (L^2 = R^2 + y^2, time 2 R).
    EXPECT_NEAR(e.value, ss[i], 5.0 * e.err + 0.01 * ss[i]) << i;
  }
}

TEST(LidarSlow, FusedModelHoldsInTheFirstMeanFreePathAndIsLowDeeper) {
  LidarSettings s;
  s.sigma_s = 1.0;
  s.sigma_a = 0.01;
  s.phase = HgPhase{0.95};
  s.thickness = 4.0;
  s.distance = 50.0;
  s.r_rx = 0.01;
  s.fov = 0.01;
  s.time_edges = {100.0, 100.5, 101.5, 104.0, 108.0};  // depths 0-0.25, 0.25-0.75, 0.75-2, 2-4
  s.photons = 3000000;
  const LidarMcResult mc = run_lidar_mc(s);
  const LidarModelResult m = lidar_mfs(s);
  const std::vector<double> ss = lidar_single_scatter(s);
  for (size_t i = 0; i < 2; ++i) {
    const Estimate& e = mc.received.bins[i];
    ASSERT_LT(e.err, 0.05 * e.value) << i;
    EXPECT_NEAR(m.bins[i], e.value, 5.0 * e.err + 0.1 * e.value) << i;  // documented: within 1-7 %
  }
  // Single scattering is far low from the second bin on (documented: 75 % at 0.75 mfp).
  EXPECT_LT(ss[1], mc.received.bins[1].value - 5.0 * mc.received.bins[1].err);
  // Deeper the model misses multiple scattering (documented: 25 % and more low by 1.75 mfp).
  EXPECT_LT(m.bins[3], mc.received.bins[3].value);
}

}  // namespace
}  // namespace nimbus
