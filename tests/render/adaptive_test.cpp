// Adaptive sampling (RenderOptions::noise, render --noise): the planner's error estimate against a direct
// computation on a film of known samples, samples sent where the variance is, the target reached,
// bit-identical for any thread count, and a cancelled adaptive render resumed equal to one made in one go.
#include "render/adaptive.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>

#include "nimbus/compare.h"
#include "nimbus/error.h"
#include "nimbus/render.h"
#include "render/film.h"
#include "support/bitwise.h"
#include "support/scenes.h"

namespace nimbus {
namespace {

// A grey probe sample of luminance `value` into pixel (x, y) of a film with the adaptive layer, costing
// `draws` random numbers.
void add_probe(Film& film, int layer, int x, int y, double value, double draws = 0.0) {
  double a[kAdaptiveChannels];
  probe_values(value, draws, a);
  film.add(layer, x, y, a);
}

// A grey image sample and a probe sample of the same luminance.
void add_grey(Film& film, int layer, int x, int y, double value, double draws = 0.0) {
  film.add_sample(x, y, Rgb(value, value, value));
  add_probe(film, layer, x, y, value, draws);
}

// Left half: every sample 1 (no variance). Right half: samples alternating 0.5 and 1.5 (variance 1/4
// for n even: the unbiased estimate is n / (4 (n - 1))).
Film two_halves(int n, int* y2) {
  Film film(8, 4);
  *y2 = film.add_layer(kAdaptiveLayer, kAdaptiveChannels);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 8; ++x)
      for (int s = 0; s < n; ++s) add_grey(film, *y2, x, y, x < 4 ? 1.0 : (s % 2 ? 1.5 : 0.5));
  return film;
}

TEST(Adaptive, EstimateIsTheBinnedRelativeErrorOfTheVariances) {
  int y2 = 0;
  const int n = 8;
  const Film film = two_halves(n, &y2);
  AdaptiveSettings s;
  s.noise = 0.01;
  s.bin = 2;
  s.max_spp = 1024;
  s.shrink = 0.0;
  s.probe_radius = 1;
  const AdaptivePlan plan = plan_adaptive_pass(film, y2, s);
  // Per-sample variance on the right: n / (4 (n - 1)), each pixel's own (not pooled: a pixel's count
  // comes from its neighbours, its part in the estimate from itself). A 2 x 2 bin's mean has variance
  // sum_i v_i / (4 n) / 4; every bin's mean luminance is 1; 4 x 2 bins, the right two columns noisy.
  const double v = n / (4.0 * (n - 1));
  const double expected = std::sqrt(4 * (4 * v) / (16.0 * n) / 8.0);
  EXPECT_NEAR(plan.estimated_error, expected, 1e-12 * expected);
  // Far above 1 %: samples go to the noisy half only (the quiet columns 0-1, whose neighbours are quiet,
  // keep their 8), at most doubling each pixel.
  for (int y = 0; y < 4; ++y) {
    EXPECT_EQ(plan.target[size_t(y) * 8 + 0], uint32_t(n));
    EXPECT_EQ(plan.target[size_t(y) * 8 + 7], uint32_t(2 * n));
  }
  EXPECT_GT(plan.new_samples, 0);
  // A target above the estimate: nothing more.
  s.noise = 1.01 * expected;
  EXPECT_EQ(plan_adaptive_pass(film, y2, s).new_samples, 0);
}

TEST(Adaptive, TargetsFollowTheStandardDeviation) {
  // With the doubling bound out of the way (n = 64, the goal close to the estimate), the planned
  // counts of the noisiest pixels equal lambda sqrt(v) / m: checked through their ratio, which is the
  // ratio of the standard deviations pooled over their neighbours (not themselves). In the top row:
  // column 5's five neighbours all have v; column 4's are columns 3 (0) and 5 (v) beside it and 3, 4,
  // 5 below it: 3v/5.
  int y2 = 0;
  const Film film = two_halves(64, &y2);
  AdaptiveSettings s;
  s.bin = 1;
  s.max_spp = 1 << 20;
  s.shrink = 0.0;
  s.probe_radius = 1;
  s.noise = plan_adaptive_pass(film, y2, s).estimated_error / 1.2;
  const AdaptivePlan plan = plan_adaptive_pass(film, y2, s);
  const double r = double(plan.target[5]) / double(plan.target[4]);
  EXPECT_NEAR(r, std::sqrt(5.0 / 3.0), 0.05);
}

TEST(Adaptive, TheImagesSamplesDecideNothing) {
  // Every pixel's probe samples alike (0.5 and 1.5); pixel (3, 3)'s image samples all 1 (no variance:
  // "converged"), or one of them 40 (a rare bright path), or like the others. The plans are the same
  // whatever the image's samples: had they decided (a pixel's count, the bins' means, the stop), the
  // quiet pixel would stop and its mean, and the image's, would be biased dark over many renders.
  auto film_with = [](double odd, double probe_odd) {
    Film film(8, 8);
    const int layer = film.add_layer(kAdaptiveLayer, kAdaptiveChannels);
    for (int y = 0; y < 8; ++y)
      for (int x = 0; x < 8; ++x)
        for (int s = 0; s < 32; ++s) {
          const double value = s % 2 ? 1.5 : 0.5, v = x == 3 && y == 3 && s == 0 ? odd : value;
          film.add_sample(x, y, Rgb(v, v, v));
          const double probe = (s / 4) % 2 ? 1.5 : 0.5;  // a probe sample for every 4 of the image's
          if (s % 4 == 0) add_probe(film, layer, x, y, x == 3 && y == 3 && s == 0 ? probe_odd : probe);
        }
    return film;
  };
  AdaptiveSettings st;
  st.bin = 2;
  st.max_spp = 1 << 20;
  const Film plain = film_with(0.5, 0.5);
  const int layer = plain.layer_index(kAdaptiveLayer);
  st.noise = plan_adaptive_pass(plain, layer, st).estimated_error / 1.2;
  const AdaptivePlan ref = plan_adaptive_pass(plain, layer, st);
  for (const double odd : {1.0, 40.0}) {
    const AdaptivePlan plan = plan_adaptive_pass(film_with(odd, 0.5), layer, st);
    EXPECT_EQ(plan.estimated_error, ref.estimated_error) << odd;
    EXPECT_EQ(plan.target, ref.target) << odd;
    EXPECT_EQ(plan.probe, ref.probe) << odd;
  }
  // The power of the check: the counts follow the probe's variance. A bright probe sample at (3, 3)
  // raises the estimate and the counts around it.
  const AdaptivePlan bright = plan_adaptive_pass(film_with(0.5, 40.0), layer, st);
  EXPECT_GT(bright.estimated_error, ref.estimated_error);
  EXPECT_GT(bright.target[4 * 8 + 4], ref.target[4 * 8 + 4]);
  EXPECT_GT(ref.target[4 * 8 + 4], 32u);
  // One probe sample planned for every probe_ratio of the image's.
  const uint32_t t = ref.target[4 * 8 + 4], q = uint32_t(st.probe_ratio);
  EXPECT_EQ(ref.probe[4 * 8 + 4], std::max(8u, (t + q - 1) / q));
}

TEST(Adaptive, CostlierPixelsTakeFewerSamples) {
  // Equal variance everywhere; the right half's samples cost 4x the left's (with the per-sample overhead):
  // the planned counts are in the ratio sqrt(cost), away from the image's edges and the middle. (The
  // right half has 32 samples, the left 64, so that both targets fall inside the doubling bound.)
  Film film(12, 3);
  const int layer = film.add_layer(kAdaptiveLayer, kAdaptiveChannels);
  const double cheap = 8.0, dear = 4.0 * (cheap + kSampleOverheadDraws) - kSampleOverheadDraws;
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 12; ++x)
      for (int s = 0; s < (x < 6 ? 64 : 32); ++s)
        add_grey(film, layer, x, y, s % 2 ? 1.5 : 0.5, x < 6 ? cheap : dear);
  AdaptiveSettings st;
  st.bin = 1;
  st.max_spp = 1 << 20;
  st.probe_radius = 1;
  st.noise = plan_adaptive_pass(film, layer, st).estimated_error / 1.2;
  const AdaptivePlan plan = plan_adaptive_pass(film, layer, st);
  EXPECT_NEAR(double(plan.target[12 + 2]) / double(plan.target[12 + 9]), 2.0, 0.05);
}

Scene adaptive_sphere_scene(int spp) {
  return test::scene_from_json("{" + test::camera_json(24, 20) + R"(,
    "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 0.8}, "sigma_s": 6.0,
               "sigma_a": 0.3, "phase": {"type": "hg", "g": 0.7}}],
    "lights": [{"type": "directional", "direction": [1, 0.5, -1], "irradiance": 3.0}],
    "film": {"layers": ["samples"]},
    "integrator": {"type": "pathtrace", "spp": )" +
                               std::to_string(spp) + R"(, "seed": 3}})");
}

const ImageChannel& samples_channel(const Image& img) {
  for (const auto& c : img.channels)
    if (c.name == "samples.X") return c;
  throw Error("no samples channel");
}

TEST(Adaptive, ReachesItsTargetAndSpendsSamplesOnTheMedium) {
  const Scene scene = adaptive_sphere_scene(1024);
  RenderOptions o;
  o.noise = 0.05;
  o.threads = 2;
  const RenderResult r = render(scene, o);
  EXPECT_LE(r.noise_estimate, 0.05);
  EXPECT_GT(r.noise_estimate, 0.0);
  EXPECT_FALSE(r.partial);
  // The empty corner (no medium in view, no environment: every sample 0) keeps the base 8 samples; the
  // sphere's centre takes more.
  const auto& n = samples_channel(r.image).data;
  EXPECT_EQ(n[0], 8.0f);
  EXPECT_GT(n[size_t(10) * 24 + 12], 8.0f);
  EXPECT_LT(r.spp_mean, double(r.spp));
  // The estimate against the truth: an adaptive render to 1 % (another seed) as the reference, its own
  // noise (its estimate) removed. Loose bounds: the estimate is itself a noisy statistic.
  RenderOptions ref_o;
  ref_o.noise = 0.01;
  ref_o.threads = 2;
  ref_o.seed = 99;
  const RenderResult ref = render(scene, ref_o);
  CompareOptions c;
  c.bin = 4;
  c.min_reference = 0.05;
  const double measured = compare_images(r.image, ref.image, c).rel_rmse;
  const double truth =
      std::sqrt(std::max(0.0, measured * measured - ref.noise_estimate * ref.noise_estimate));
  EXPECT_GT(truth, 0.4 * r.noise_estimate);
  EXPECT_LT(truth, 2.0 * r.noise_estimate);
}

TEST(Adaptive, BitIdenticalForAnyThreadCountAndWhenResumed) {
  const Scene scene = adaptive_sphere_scene(256);
  RenderOptions one;
  one.noise = 0.08;
  one.threads = 1;
  const RenderResult whole = render(scene, one);
  RenderOptions two = one;
  two.threads = 2;
  two.tile_size = 5;
  EXPECT_TRUE(test::same_floats(whole.image.rgb, render(scene, two).image.rgb));
  // Cancelled part-way through a later pass: the film of the last whole pass; resumed with the same
  // target, the render made in one go.
  std::atomic<bool> cancel{false};
  RenderOptions stop = two;
  stop.cancel = &cancel;
  stop.progress = [&](int64_t done, int64_t, int64_t) {
    if (done > int64_t(24) * 20 * 12) cancel = true;
  };
  const RenderResult part = render(scene, stop);
  ASSERT_TRUE(part.partial);
  ASSERT_GT(part.spp, 0);
  RenderOptions rest = two;
  rest.resume = &part.state;
  const RenderResult resumed = render(scene, rest);
  EXPECT_TRUE(test::same_floats(whole.image.rgb, resumed.image.rgb));
  EXPECT_FALSE(test::same_floats(part.image.rgb, resumed.image.rgb));
  // A render made without a noise target cannot be continued adaptively.
  RenderOptions plain;
  plain.spp = 4;
  const RenderResult uniform = render(scene, plain);
  RenderOptions bad = two;
  bad.resume = &uniform.state;
  EXPECT_THROW(render(scene, bad), Error);
}

}  // namespace
}  // namespace nimbus
