// The generalised propagator's delay (gsa_delay.h) against photon Monte Carlo at small optical depth
// (issue 14): the light that never travelled backward, for a Gaussian peak (where the small-angle
// moments are exact to leading order: asserted within the neglected order <theta^2>), HG 0.9 and 0.95,
// a double HG and the cloud Mie table (measured and printed, not asserted: there the model fails both
// ways, wide deflections delay more than theta^2 / 2 and backward ones count in m2 but not in the
// forward light).  Numbers in docs/validation/time.md.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "media/phase.h"
#include "transport/gsa_delay.h"
#include "transport/phase_spec.h"
#include "transport/photon_mc.h"

namespace nimbus {
namespace {

struct Case {
  std::string spec;
  bool leading_order_exact;
};

TEST(GsaDelaySlow, ForwardLightAgainstTheCompoundPoissonMoments) {
  const std::vector<Case> cases{{"gauss:0.0005", true},
                                {"hg:0.9", false},
                                {"hg:0.95", false},
                                {"dhg:0.95,-0.3,0.9", false},
                                {"mie:cloud_mie_550nm", false}};
  for (const Case& c : cases) {
    const Phase phase = parse_phase_spec(c.spec);
    const DeflectionMoments dm = deflection_moments(phase);
    PhotonMcSettings s;
    s.phase = phase;
    s.thickness = 1.5;  // matched faces end the walks
    s.plane_depths = {0.1, 0.25, 1.0};
    s.photons = 400000;
    s.batches = 20;
    s.seed = 3;
    s.time_edges = {0.0, 1e-4, 1e-3, 1e-2, 1e-1, 1.0};
    const PhotonMcResult r = run_photon_mc(s);
    std::printf("%s: m2 %.4e m4 %.4e (m4 / m2^2 = %.1f; Gaussian 2)\n", c.spec.c_str(), dm.m2, dm.m4,
                dm.m4 / (dm.m2 * dm.m2));
    for (const PlaneTally& t : r.planes) {
      const GammaDelayLaw g = gsa_delay_law(t.depth, 1.0, 0.0, dm);
      const Estimate& mean = t.delay_mean_forward_only;
      const Estimate& var = t.delay_variance_forward_only;
      std::printf(
          "  bz %.2f: mean mc_fwd %.4e +- %.1e gsa %.4e (%+.1f %%) | var mc_fwd %.4e +- %.1e gsa %.4e "
          "(%+.1f %%) | all light mean %.4e\n",
          t.depth, mean.value, mean.err, g.mean(), 100.0 * (mean.value / g.mean() - 1.0), var.value, var.err,
          g.variance(), 100.0 * (var.value / g.variance() - 1.0), t.delay_mean.value);
      // The bins against the gamma law (all scattered light; shape only moment-matched).
      std::printf("    bins mc / gamma:");
      for (size_t i = 0; i < t.delay.bins.size(); ++i)
        std::printf(" %.3e/%.3e", t.delay.bins[i].value, g.within(s.time_edges[i], s.time_edges[i + 1]));
      std::printf("\n");
      if (c.leading_order_exact) {
        EXPECT_LT(mean.err, 0.03 * mean.value);                              // power
        const double angle2 = dm.m2 * t.depth / (1.0 - std::exp(-t.depth));  // <theta^2> at the plane
        EXPECT_NEAR(mean.value, g.mean(), 5.0 * mean.err + angle2 * g.mean()) << t.depth;
        EXPECT_NEAR(var.value, g.variance(), 5.0 * var.err + 2.0 * angle2 * g.variance()) << t.depth;
      }
    }
  }
}

}  // namespace
}  // namespace nimbus
