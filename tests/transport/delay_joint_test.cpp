// The photon Monte Carlo's joint delay x angle and delay x radius tallies (issue 14): their marginals are
// the 1-D tallies of the same photons (to rounding), the crossings outside the angle or radius edges are
// kept, and asking for them changes no other tally; the forward-only delay bins are part of the delay bins.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "core/math.h"
#include "media/phase.h"
#include "nimbus/error.h"
#include "transport/photon_mc.h"

namespace nimbus {
namespace {

PhotonMcSettings joint_run() {
  PhotonMcSettings s;
  s.phase = HgPhase{0.9};
  s.sigma_a = 0.05;
  s.thickness = 3.0;
  s.plane_depths = {0.5, 1.5};
  s.theta_edges = {0.0, 0.05, 0.2, 0.6, 1.2};  // forward crossings beyond 1.2 rad fall outside
  s.r_edges = {0.05, 0.2, 0.5, 1.0};           // and those within 0.05 or beyond 1 of the axis
  s.photons = 20000;
  s.batches = 10;
  for (int i = 0; i <= 20; ++i) s.time_edges.push_back(0.05 * i);
  s.joint_angle = s.joint_radius = true;
  return s;
}

double slot(const TimeTally& t, size_t j) {  // 0: before, 1..N: bins, N + 1: after
  return j == 0 ? t.before.value : j <= t.bins.size() ? t.bins[j - 1].value : t.after.value;
}

TEST(DelayJoint, MarginalsAreTheOneDimensionalTalliesOfTheSamePhotons) {
  const PhotonMcSettings s = joint_run();
  const PhotonMcResult r = run_photon_mc(s);
  PhotonMcSettings plain = s;
  plain.joint_angle = plain.joint_radius = false;
  const PhotonMcResult q = run_photon_mc(plain);
  const size_t TS = s.time_edges.size() + 1;
  for (size_t k = 0; k < r.planes.size(); ++k) {
    const PlaneTally& t = r.planes[k];
    ASSERT_EQ(t.delay_angle.size(), s.theta_edges.size());  // the bins and the outside slot
    ASSERT_EQ(t.delay_radius.size(), s.r_edges.size());
    // Over angle (or radius): the delay tally, slot by slot.
    for (size_t j = 0; j < TS; ++j) {
      double sa = 0.0, sr = 0.0;
      for (const TimeTally& x : t.delay_angle) sa += slot(x, j);
      for (const TimeTally& x : t.delay_radius) sr += slot(x, j);
      EXPECT_NEAR(sa, slot(t.delay, j), 1e-12 * t.delay_weight.value) << k << " " << j;
      EXPECT_NEAR(sr, slot(t.delay, j), 1e-12 * t.delay_weight.value) << k << " " << j;
    }
    // Over delay: the radial tally times the annulus area.
    for (size_t i = 0; i + 1 < s.r_edges.size(); ++i) {
      double v = 0.0;
      for (size_t j = 0; j < TS; ++j) v += slot(t.delay_radius[i], j);
      const double area = kPi * (s.r_edges[i + 1] * s.r_edges[i + 1] - s.r_edges[i] * s.r_edges[i]);
      EXPECT_NEAR(v / area, t.radial[i].value, 1e-12 * t.radial[i].value) << k << " " << i;
      EXPECT_GT(v, 0.0);
    }
    // Over delay, angle bin i: the forward flux, sum of w, while angular[i] is the sum of w / cos theta
    // per sr; every crossing has cos(hi) <= cos theta < cos(lo), which brackets one by the other.
    for (size_t i = 0; i + 1 < s.theta_edges.size(); ++i) {
      double v = 0.0;
      for (size_t j = 0; j < TS; ++j) v += slot(t.delay_angle[i], j);
      const double omega = 2.0 * kPi * (std::cos(s.theta_edges[i]) - std::cos(s.theta_edges[i + 1]));
      const double per_sr = v / omega, rad = t.angular[i].value;
      EXPECT_GE(per_sr, std::cos(s.theta_edges[i + 1]) * rad * (1.0 - 1e-12)) << k << " " << i;
      EXPECT_LE(per_sr, std::cos(s.theta_edges[i]) * rad * (1.0 + 1e-12)) << k << " " << i;
      EXPECT_GT(v, 0.0);
    }
    // Power: the outside slots hold light (the edges leave some out).
    double out_a = 0.0, out_r = 0.0;
    for (size_t j = 0; j < TS; ++j) {
      out_a += slot(t.delay_angle.back(), j);
      out_r += slot(t.delay_radius.back(), j);
    }
    EXPECT_GT(out_a, 0.0);
    EXPECT_GT(out_r, 0.0);
    // The joint tallies change nothing else.
    const PlaneTally& u = q.planes[k];
    EXPECT_TRUE(u.delay_angle.empty() && u.delay_radius.empty());
    for (size_t j = 0; j < TS; ++j) EXPECT_EQ(slot(u.delay, j), slot(t.delay, j));
    for (size_t i = 0; i < t.angular.size(); ++i) EXPECT_EQ(u.angular[i].value, t.angular[i].value);
    EXPECT_EQ(u.delay_mean.value, t.delay_mean.value);
  }
}

TEST(DelayJoint, ForwardOnlyDelayBinsArePartOfTheDelayBins) {
  PhotonMcSettings s = joint_run();
  s.joint_angle = s.joint_radius = false;
  s.thickness = std::numeric_limits<double>::infinity();  // photons that wander deep and return
  const PhotonMcResult r = run_photon_mc(s);
  const size_t TS = s.time_edges.size() + 1;
  for (const PlaneTally& t : r.planes) {
    double all = 0.0, fwd = 0.0;
    for (size_t j = 0; j < TS; ++j) {
      EXPECT_LE(slot(t.delay_forward_only, j), slot(t.delay, j) * (1.0 + 1e-12)) << j;
      all += slot(t.delay, j);
      fwd += slot(t.delay_forward_only, j);
    }
    EXPECT_NEAR(all, t.delay_weight.value, 1e-12 * all);
    EXPECT_NEAR(fwd, t.delay_weight_forward_only.value, 1e-12 * fwd);
    // Power: some light has turned back on its way, and the rest is most of it.
    EXPECT_LT(fwd, all - 10.0 * t.delay_weight.err);
    EXPECT_GT(fwd, 0.5 * all);
  }
}

TEST(DelayJoint, NeedTimeEdgesAndFitInMemory) {
  PhotonMcSettings s = joint_run();
  s.time_edges.clear();
  EXPECT_THROW(run_photon_mc(s), Error);
  s = joint_run();
  s.time_edges.clear();
  for (int i = 0; i <= 100000; ++i) s.time_edges.push_back(i);
  s.theta_edges.clear();
  for (int i = 0; i <= 1000; ++i) s.theta_edges.push_back(kPi * i / 1000.0);
  EXPECT_THROW(run_photon_mc(s), Error);  // 1e5 x 1e3 x 4 slots x 10 batches: far over 1 GiB
}

}  // namespace
}  // namespace nimbus
