// The lidar return (src/transport/lidar.h): the photon Monte Carlo against the single-scatter lidar
// equation at small optical depth, causality, its time integral against an independent analog tally,
// microscopic Beer-Lambert, thread independence; the closed forms against quadratures; the fused model's
// single-scatter limit; bad settings.
#include "transport/lidar.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <vector>

#include "core/math.h"
#include "nimbus/error.h"

namespace nimbus {
namespace {

LidarSettings thin_settings() {
  LidarSettings s;
  s.sigma_s = 0.1;
  s.sigma_a = 0.02;
  s.phase = HgPhase{0.9};
  s.thickness = 2.0;
  s.distance = 0.5;
  s.r_rx = 0.0;
  s.fov = 0.002;
  for (int i = 0; i <= 8; ++i) s.time_edges.push_back(1.0 + 0.5 * i);  // ranges 0.5 .. 2.5
  s.photons = 400000;
  s.seed = 7;
  return s;
}

// Simpson's rule for the single-scatter equation: b p(pi) e^{-2 c (R - d)} min(1, (R tan fov / r)^2) / R^2.
double single_scatter_by_quadrature(const LidarSettings& s, double R1, double R2) {
  const double c = s.sigma_s + s.sigma_a, pb = hg_eval(-1.0, 0.9);
  auto f = [&](double R) {
    const double ov = s.r_rx > 0.0 ? std::min(1.0, std::pow(R * std::tan(s.fov) / s.r_rx, 2)) : 1.0;
    return s.sigma_s * pb * std::exp(-2.0 * c * (R - s.distance)) * ov / (R * R);
  };
  const int N = 20000;
  const double h = (R2 - R1) / N;
  double sum = f(R1) + f(R2);
  for (int i = 1; i < N; ++i) sum += f(R1 + i * h) * (i % 2 ? 4.0 : 2.0);
  return sum * h / 3.0;
}

TEST(Lidar, DiskOverlapAreaClosedForms) {
  EXPECT_DOUBLE_EQ(disk_overlap_area(1.0, 2.0, 0.5), kPi);  // the small disk inside the large one
  EXPECT_EQ(disk_overlap_area(1.0, 2.0, 3.0), 0.0);
  EXPECT_EQ(disk_overlap_area(0.0, 2.0, 0.0), 0.0);
  // Two unit disks one radius apart: 2 pi / 3 - sqrt(3) / 2.
  EXPECT_NEAR(disk_overlap_area(1.0, 1.0, 1.0), 2.0 * kPi / 3.0 - std::sqrt(3.0) / 2.0, 1e-12);
  // Continuous where one disk starts to leave the other.
  EXPECT_NEAR(disk_overlap_area(1.0, 2.0, 1.0 + 1e-9), kPi, 1e-6);
}

TEST(Lidar, SingleScatterClosedFormMatchesQuadrature) {
  for (double r : {0.0, 0.01}) {
    for (double d : {0.0, 40.0}) {
      LidarSettings s = thin_settings();
      s.sigma_s = 2.0;  // large optical depths: exercise E1 at large arguments
      s.r_rx = r;
      s.distance = d;
      s.thickness = 3.0;
      s.time_edges = {2.0 * d + 0.1, 2.0 * d + 0.5, 2.0 * d + 1.3, 2.0 * d + 2.9, 2.0 * d + 5.9};
      const std::vector<double> v = lidar_single_scatter(s);
      for (size_t i = 0; i < v.size(); ++i) {
        const double R1 = s.time_edges[i] / 2.0, R2 = std::min(s.time_edges[i + 1] / 2.0, d + s.thickness);
        const double q = single_scatter_by_quadrature(s, R1, R2);
        EXPECT_NEAR(v[i], q, 1e-9 * q) << "r " << r << " d " << d << " bin " << i;
      }
    }
  }
}

TEST(Lidar, FusedModelReducesToSingleScatterAsScatteringVanishes) {
  double previous = 0.0;
  for (double b : {1e-2, 1e-3, 1e-4}) {
    LidarSettings s = thin_settings();
    s.sigma_s = b;
    s.sigma_a = 0.0;
    s.fov = 0.05;
    const LidarModelResult m = lidar_mfs(s);
    const std::vector<double> ss = lidar_single_scatter(s);
    double worst = 0.0;
    for (size_t i = 0; i < ss.size(); ++i) {
      EXPECT_GE(m.bins[i], ss[i] * (1.0 - 1e-12));  // the model adds light, never removes it
      worst = std::max(worst, (m.bins[i] - ss[i]) / ss[i]);
    }
    EXPECT_LT(worst, 50.0 * b) << b;  // the scattered legs are O(b z) of the single-scatter return
    if (previous > 0.0) {
      EXPECT_NEAR(worst / previous, 0.1, 0.03) << b;  // ... and linear in b
    }
    previous = worst;
  }
}

TEST(Lidar, McAtSmallOpticalDepthIsTheSingleScatterEquation) {
  const LidarSettings s = thin_settings();
  const LidarMcResult mc = run_lidar_mc(s);
  const std::vector<double> ss = lidar_single_scatter(s);
  for (size_t i = 0; i < ss.size(); ++i) {
    const Estimate& e = mc.received.bins[i];
    EXPECT_LT(e.err, 0.03 * ss[i]) << i;  // the test has power
    EXPECT_NEAR(e.value, ss[i], 5.0 * e.err) << i;
  }
  EXPECT_EQ(mc.received.before.value, 0.0);  // nothing from the clear gap
}

TEST(Lidar, McIsCausal) {
  // Light that went deeper than D returns after 2 n (d + D): the bins before that are the same photons'
  // tallies for thickness D and 2 D, bit for bit; nothing arrives before 2 n d.
  LidarSettings s = thin_settings();
  s.sigma_s = 1.0;
  s.n = 1.33;
  s.fov = 0.3;
  s.photons = 20000;
  s.time_edges.clear();
  for (int i = 0; i <= 40; ++i) s.time_edges.push_back(0.2 * i);
  const LidarMcResult a = run_lidar_mc(s);
  s.thickness *= 2.0;
  const LidarMcResult b = run_lidar_mc(s);
  const double t_d = 2.0 * s.n * s.distance, t_D = 2.0 * s.n * (s.distance + 0.5 * s.thickness);
  int compared = 0;
  for (size_t i = 0; i + 1 < s.time_edges.size(); ++i) {
    if (s.time_edges[i + 1] <= t_d) {
      EXPECT_EQ(a.received.bins[i].value, 0.0) << i;
    }
    if (s.time_edges[i + 1] <= t_D) {
      EXPECT_EQ(a.received.bins[i].value, b.received.bins[i].value) << i;
      compared += a.received.bins[i].value > 0.0;
    }
  }
  EXPECT_GE(compared, 10);
  double later = 0.0;  // the deeper slab adds light after 2 n (d + D)
  for (size_t i = 0; i + 1 < s.time_edges.size(); ++i)
    if (s.time_edges[i] >= t_D) later += b.received.bins[i].value - a.received.bins[i].value;
  EXPECT_GT(later, 0.0);
}

TEST(Lidar, McTimeIntegralEqualsAnIndependentAnalogTally) {
  LidarSettings s = thin_settings();
  s.sigma_s = 1.0;
  s.sigma_a = 0.1;
  s.phase = HgPhase{0.8};
  s.distance = 1.0;
  s.r_rx = 0.5;
  s.fov = 0.5;
  s.photons = 200000;
  const LidarMcResult mc = run_lidar_mc(s);
  double sum = mc.received.before.value + mc.received.after.value;
  for (const Estimate& e : mc.received.bins) sum += e.value;
  EXPECT_NEAR(sum, mc.total.value, 1e-12 * sum);
  EXPECT_LT(mc.analog.err, 0.05 * mc.analog.value);
  EXPECT_NEAR(mc.total.value, mc.analog.value, 5.0 * std::hypot(mc.total.err, mc.analog.err));
}

TEST(Lidar, McMicroscopicBeerLambert) {
  // With absorption a, each bin holds the absorption-free run's light weighted by exp(-a s), s the path
  // inside the slab: t minus the clear gap out and back (n = 1).
  LidarSettings s = thin_settings();
  s.sigma_s = 1.0;
  s.sigma_a = 0.0;
  s.thickness = 3.0;
  s.phase = HgPhase{0.5};  // a mild forward peak: a local estimate of low variance
  s.fov = 0.1;
  s.photons = 200000;
  s.time_edges.clear();
  for (int i = 0; i <= 16; ++i) s.time_edges.push_back(1.0 + 0.25 * i);
  const LidarMcResult clear = run_lidar_mc(s);
  s.sigma_a = 0.3;
  s.seed = 8;
  const LidarMcResult absorbing = run_lidar_mc(s);
  int powerful = 0;
  for (size_t i = 0; i + 1 < s.time_edges.size(); ++i) {
    const double t = 0.5 * (s.time_edges[i] + s.time_edges[i + 1]),
                 w = std::exp(-s.sigma_a * (t - 2.0 * s.distance));
    const Estimate &c = clear.received.bins[i], &a = absorbing.received.bins[i];
    EXPECT_NEAR(a.value, w * c.value, 5.0 * std::hypot(a.err, w * c.err) + 2e-3 * a.value) << t;
    powerful += a.err < 0.05 * a.value;
  }
  EXPECT_GE(powerful, 10);
}

TEST(Lidar, McIsTheSameForAnyNumberOfThreads) {
  LidarSettings s = thin_settings();
  s.sigma_s = 1.0;
  s.photons = 5000;
  const LidarMcResult many = run_lidar_mc(s);
  LidarMcResult one;
  {
    tbb::global_control only(tbb::global_control::max_allowed_parallelism, 1);
    one = run_lidar_mc(s);
  }
  for (size_t i = 0; i < many.received.bins.size(); ++i) {
    EXPECT_EQ(many.received.bins[i].value, one.received.bins[i].value);
    EXPECT_EQ(many.received.bins[i].err, one.received.bins[i].err);
  }
}

TEST(Lidar, RejectsBadSettings) {
  auto rejects = [](auto change) {
    LidarSettings s = thin_settings();
    change(s);
    EXPECT_THROW(run_lidar_mc(s), Error);
    EXPECT_THROW(lidar_mfs(s), Error);
  };
  rejects([](LidarSettings& s) { s.fov = 0.0; });
  rejects([](LidarSettings& s) { s.fov = 2.0; });
  rejects([](LidarSettings& s) { s.r_rx = -1.0; });
  rejects([](LidarSettings& s) { s.distance = -1.0; });
  rejects([](LidarSettings& s) { s.thickness = INFINITY; });
  rejects([](LidarSettings& s) { s.time_edges = {1.0}; });
  rejects([](LidarSettings& s) { s.time_edges = {1.0, 0.5}; });
  rejects([](LidarSettings& s) { s.time_edges = {-1.0, 0.5}; });
  rejects([](LidarSettings& s) { s.n = 0.5; });
}

}  // namespace
}  // namespace nimbus
