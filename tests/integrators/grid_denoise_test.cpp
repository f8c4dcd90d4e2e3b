// The scatter grid's denoising (integrators/grid_denoise.h): on synthetic grids of known truth made of 8
// noisy batches, it lowers the noise of a smooth field, keeps a step far above the noise, leaves the
// nodes outside the media alone (and out of their neighbours' smoothing), and changes nothing without
// noise.
#include "integrators/grid_denoise.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "core/math.h"
#include "core/rng.h"

namespace nimbus {
namespace {

constexpr int kBatches = 8;

struct Synthetic {
  NodeGrid grid;
  FloatArray values, per_batch, truth;  // 2 floats per node (the second twice the first), 1 probe
};

// Truth f per node; batch b's share f / 8 plus Gaussian noise of standard deviation sigma / sqrt(8), so
// that each node's sum has noise sigma.
Synthetic synthetic(int n, const std::function<double(int, int, int)>& f, double sigma, uint64_t seed) {
  Synthetic s;
  s.grid.nodes = {n, n, n};
  s.grid.bounds = Bounds{Vec3(0.0), Vec3(double(n - 1))};
  s.values = FloatArray(s.grid.size() * 2);
  s.truth = FloatArray(s.grid.size());
  s.per_batch = FloatArray(s.grid.size() * kBatches);
  Rng rng(seed, 0);
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const size_t i = s.grid.index(x, y, z);
        s.truth[i] = float(f(x, y, z));
        double sum = 0.0;
        for (int b = 0; b < kBatches; ++b) {
          const double u1 = std::max(rng.uniform(), 1e-12), u2 = rng.uniform();
          const double g = std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * kPi * u2);
          const float share = float(f(x, y, z) / kBatches + g * sigma / std::sqrt(double(kBatches)));
          s.per_batch[i * kBatches + size_t(b)] = share;
          sum += share;
        }
        s.values[2 * i] = float(sum);
        s.values[2 * i + 1] = float(2.0 * sum);
      }
  return s;
}

// RMS of values[2 i] - truth over the nodes at least `margin` from the grid's faces.
double rms_error(const Synthetic& s, int margin) {
  const int n = s.grid.nodes[0];
  double sq = 0.0;
  int count = 0;
  for (int z = margin; z < n - margin; ++z)
    for (int y = margin; y < n - margin; ++y)
      for (int x = margin; x < n - margin; ++x, ++count) {
        const size_t i = s.grid.index(x, y, z);
        sq += std::pow(double(s.values[2 * i]) - double(s.truth[i]), 2);
      }
  return std::sqrt(sq / count);
}

TEST(GridDenoise, LowersTheNoiseOfASmoothField) {
  Synthetic s = synthetic(
      16, [](int x, int y, int z) { return 1.0 + 0.02 * x - 0.01 * y + 0.005 * z; }, 0.05, 7);
  const double before = rms_error(s, 2);
  EXPECT_NEAR(before, 0.05, 0.005);  // the noise as made
  denoise_grid(&s.values, s.grid, 2, s.per_batch, kBatches, {0}, std::vector<uint8_t>(s.grid.size(), 1));
  const double after = rms_error(s, 2);
  // The smoothing alone (8 passes of the quadratic filter per axis) takes independent noise to about a
  // fifth of itself; the Wiener share keeps a little more.
  EXPECT_LT(after, 0.35 * before) << before << " -> " << after;
  for (size_t i = 0; i < s.grid.size(); ++i)  // every float of a node alike
    ASSERT_NEAR(s.values[2 * i + 1], 2.0f * s.values[2 * i], 1e-5f * std::abs(s.values[2 * i + 1]) + 1e-6f);
}

TEST(GridDenoise, KeepsAQuadraticFieldsCurvature) {
  // A bowl (second derivative 0.02 per axis) under noise: a smoothing of variance s^2 nodes^2 per axis would
  // raise it by 0.03 s^2 (the binomial [1 4 6 4 1] / 16: 0.03); the quadratic filter leaves it.
  const auto bowl = [](int x, int y, int z) {
    const double dx = x - 7.5, dy = y - 7.5, dz = z - 7.5;
    return 1.0 + 0.01 * (dx * dx + dy * dy + dz * dz);
  };
  double bias = 0.0;
  int count = 0;
  for (uint64_t seed = 1; seed <= 4; ++seed) {
    Synthetic s = synthetic(16, bowl, 0.05, seed);
    denoise_grid(&s.values, s.grid, 2, s.per_batch, kBatches, {0}, std::vector<uint8_t>(s.grid.size(), 1));
    for (size_t i = 0; i < s.grid.size(); ++i, ++count) bias += double(s.values[2 * i]) - double(s.truth[i]);
  }
  EXPECT_LT(std::abs(bias / count), 0.003) << "mean error " << bias / count;
}

TEST(GridDenoise, KeepsAStepFarAboveTheNoise) {
  const auto step = [](int x, int, int) { return x < 8 ? 1.0 : 3.0; };
  Synthetic s = synthetic(16, step, 0.01, 11);
  denoise_grid(&s.values, s.grid, 2, s.per_batch, kBatches, {0}, std::vector<uint8_t>(s.grid.size(), 1));
  // Smoothing alone would move the nodes beside the step by 0.6 (and the next ones by 0.1).
  double worst = 0.0;
  for (size_t i = 0; i < s.grid.size(); ++i)
    worst = std::max(worst, std::abs(double(s.values[2 * i]) - double(s.truth[i])));
  EXPECT_LT(worst, 0.12) << "a node moved by " << worst;
}

TEST(GridDenoise, LeavesTheNodesOutsideAlone) {
  // Inside: x < 8, a constant 1 with noise; outside: 100 (what the media's surroundings might hold).
  const auto f = [](int x, int, int) { return x < 8 ? 1.0 : 100.0; };
  Synthetic s = synthetic(16, f, 0.05, 13);
  std::vector<uint8_t> inside(s.grid.size(), 0);
  for (int z = 0; z < 16; ++z)
    for (int y = 0; y < 16; ++y)
      for (int x = 0; x < 8; ++x) inside[s.grid.index(x, y, z)] = 1;
  const FloatArray before = s.values;
  denoise_grid(&s.values, s.grid, 2, s.per_batch, kBatches, {0}, inside);
  double sq = 0.0;
  int count = 0;
  for (size_t i = 0; i < s.grid.size(); ++i) {
    if (!inside[i]) {
      ASSERT_EQ(s.values[2 * i], before[2 * i]);
      ASSERT_EQ(s.values[2 * i + 1], before[2 * i + 1]);
      continue;
    }
    sq += std::pow(double(s.values[2 * i]) - 1.0, 2);
    ++count;
  }
  EXPECT_LT(std::sqrt(sq / count), 0.5 * 0.05);  // less noise, and nothing of the 100 beside them
}

TEST(GridDenoise, ChangesNothingWithoutNoise) {
  Synthetic s = synthetic(
      12, [](int x, int y, int z) { return 1.0 + std::sin(0.7 * x) * std::cos(0.4 * y) + 0.1 * z; }, 0.0, 17);
  const FloatArray before = s.values;
  denoise_grid(&s.values, s.grid, 2, s.per_batch, kBatches, {0}, std::vector<uint8_t>(s.grid.size(), 1));
  for (size_t i = 0; i < s.values.size(); ++i)
    ASSERT_NEAR(s.values[i], before[i], 1e-5f * std::abs(before[i]) + 1e-6f) << "float " << i;
}

TEST(GridDenoise, MismatchedSizesChangeNothing) {
  Synthetic s = synthetic(
      6, [](int, int, int) { return 1.0; }, 0.1, 19);
  const FloatArray before = s.values;
  s.per_batch.resize(s.per_batch.size() - 1);
  denoise_grid(&s.values, s.grid, 2, s.per_batch, kBatches, {0}, std::vector<uint8_t>(s.grid.size(), 1));
  for (size_t i = 0; i < s.values.size(); ++i) ASSERT_EQ(s.values[i], before[i]);
}

}  // namespace
}  // namespace nimbus
