// Time-resolved photon Monte Carlo against closed forms that can fail (issue 14): the late-time decay of
// the diffuse reflectance of a thick isotropic slab against the diffusion solution (Patterson, Chance &
// Wilson 1989, extrapolated boundary), and the delay of light crossing a plane against the small-angle
// moments for a Gaussian forward peak.  Tolerances from the estimated standard errors.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <utility>
#include <vector>

#include "media/phase.h"
#include "transport/photon_mc.h"
#include "transport/time_resolved.h"

namespace nimbus {
namespace {

// Weighted least-squares slope of y against x, and its standard error.
std::pair<double, double> fit_slope(const std::vector<double>& x, const std::vector<double>& y,
                                    const std::vector<double>& sy) {
  double sw = 0.0, sx = 0.0, sy_ = 0.0;
  for (size_t i = 0; i < x.size(); ++i) {
    const double w = 1.0 / (sy[i] * sy[i]);
    sw += w;
    sx += w * x[i];
    sy_ += w * y[i];
  }
  const double xm = sx / sw, ym = sy_ / sw;
  double sxx = 0.0, sxy = 0.0;
  for (size_t i = 0; i < x.size(); ++i) {
    const double w = 1.0 / (sy[i] * sy[i]);
    sxx += w * (x[i] - xm) * (x[i] - xm);
    sxy += w * (x[i] - xm) * (y[i] - ym);
  }
  return {sxy / sxx, std::sqrt(1.0 / sxx)};
}

TEST(TimeResolvedSlow, LateReflectanceDecaysAsDiffusionPredicts) {
  // Isotropic scattering (mu_s' = mu_s = 1), no absorption, matched boundary (A = 1), 40 mfp thick: the
  // far face adds an image at ~80 mfp, exp(-80^2 / (4 D t)) < 1e-13 for t < 150.  Diffusion holds for
  // t >> 1/mu_s'; the late-time log-slope d ln R / d ln t -> -3/2 (+ z-terms of order 1/t).
  PhotonMcSettings s;
  s.sigma_s = 1.0;
  s.sigma_a = 0.0;
  s.phase = HgPhase{0.0};
  s.thickness = 40.0;
  s.photons = 400000;
  s.batches = 20;
  for (int i = 0; i <= 40; ++i) s.time_edges.push_back(0.5 * std::pow(400.0, i / 40.0));  // 0.5 .. 200
  const PhotonMcResult r = run_photon_mc(s);
  std::vector<double> x, y, sy, ym;
  double ratio_sum = 0.0, ratio_w = 0.0;
  for (size_t i = 0; i + 1 < s.time_edges.size(); ++i) {
    const double lo = s.time_edges[i], hi = s.time_edges[i + 1];
    const Estimate& e = r.reflect_time.bins[i];
    // The model's bin integral by the midpoint rule on 200 sub-bins.
    double model = 0.0;
    for (int k = 0; k < 200; ++k)
      model += diffusion_reflectance_rate(lo + (hi - lo) * (k + 0.5) / 200, 1.0, 0.0, 1.0) * (hi - lo) / 200;
    std::printf("t %7.2f..%7.2f  mc %.4e +- %.1e  diffusion %.4e  ratio %.3f\n", lo, hi, e.value, e.err,
                model, e.value / model);
    if (lo < 20.0 || hi > 150.0) continue;
    const double tm = std::sqrt(lo * hi);
    x.push_back(std::log(tm));
    y.push_back(std::log(e.value / (hi - lo)));
    sy.push_back(e.err / e.value);
    ym.push_back(std::log(model / (hi - lo)));
    ratio_sum += e.value / model / (sy.back() * sy.back());
    ratio_w += 1.0 / (sy.back() * sy.back());
  }
  const auto [slope, err] = fit_slope(x, y, sy);
  const auto [model_slope, unused] = fit_slope(x, ym, sy);
  std::printf("late slope: mc %.4f +- %.4f, diffusion %.4f; amplitude mc/diffusion %.4f\n", slope, err,
              model_slope, ratio_sum / ratio_w);
  EXPECT_LT(err, 0.05);  // power: the slope is known to a few percent
  EXPECT_NEAR(slope, model_slope, 5.0 * err);
}

TEST(TimeResolvedSlow, BeamDelayMatchesTheSmallAngleMoments) {
  // A Gaussian forward peak (theta2 = 0.0005 per component: the small-angle expansion's own assumption)
  // at optical depths 0.25, 1 and 3 (b = 1; a slab 3.5 thick with matched faces ends the walks).  Without
  // absorption the mean delay of the scattered light is exactly theta2 b z^2 / (2 (1 - exp(-b z))) in
  // the small-angle limit, for the MFS kernel too; the variance is the compound-Poisson one.  The photon
  // tracer's delay is (1 - cos theta) / cos theta per unit depth, not |gamma|^2 / 2, and it scatters
  // b / cos theta per unit depth: terms of relative order <theta^2> = 2 T z (the mean square polar angle
  // at the plane; 0.3 % at bz = 3), allowed beside the 5 sigma (twice for the variance, a fourth moment).
  // With theta2 = 0.002 the same run measures +1.4 % (mean) and +7 % (variance) at bz = 3
  // (docs/validation/time.md).
  const double theta2 = 0.0005;
  for (double a : {0.0, 0.05}) {
    PhotonMcSettings s;
    s.sigma_s = 1.0;
    s.sigma_a = a;
    s.phase = make_gauss_phase(theta2);
    s.thickness = 3.5;
    s.plane_depths = {0.25, 1.0, 3.0};
    s.photons = 400000;
    s.batches = 20;
    for (int i = 0; i <= 40; ++i) s.time_edges.push_back(0.001 * i);
    const PhotonMcResult r = run_photon_mc(s);
    for (const PlaneTally& t : r.planes) {
      const DelayMoments mfs = mfs_delay_moments(t.depth, 1.0, a, theta2);
      const DelayMoments poi = poisson_delay_moments(t.depth, 1.0, theta2);
      std::printf(
          "a %.2f z %.2f: mean mc %.5e +- %.1e mfs %.5e poisson %.5e | var mc %.4e +- %.1e mfs %.4e "
          "poisson %.4e\n",
          a, t.depth, t.delay_mean_forward_only.value, t.delay_mean_forward_only.err, mfs.mean, poi.mean,
          t.delay_variance_forward_only.value, t.delay_variance_forward_only.err, mfs.variance, poi.variance);
      // The photons that never travelled backward: the light the small-angle expansion describes.
      const Estimate& mean = t.delay_mean_forward_only;
      const Estimate& var = t.delay_variance_forward_only;
      EXPECT_LT(mean.err, 0.02 * mfs.mean);                                       // power
      const double angle2 = 2.0 * theta2 * t.depth / (1.0 - std::exp(-t.depth));  // 2 T z
      if (a == 0.0) {
        EXPECT_NEAR(mean.value, mfs.mean, 5.0 * mean.err + angle2 * mfs.mean) << t.depth;
        EXPECT_NEAR(var.value, poi.variance, 5.0 * var.err + 2.0 * angle2 * poi.variance) << t.depth;
        // Power: the Gaussian measure's variance is 2 to 2.6 times too small here, and that is seen.
        EXPECT_GT(var.value - mfs.variance, 10.0 * var.err) << t.depth;
      }
    }
  }
}

}  // namespace
}  // namespace nimbus
