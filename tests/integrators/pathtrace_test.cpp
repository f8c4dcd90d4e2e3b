// The reference path tracer against analytic answers and independent quadratures. Tolerances come
// from the estimated standard error of each Monte Carlo mean (5 sigma), never from stored results.
#include "integrators/pathtrace.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "integrators/registry.h"
#include "integrators/tracking.h"
#include "nimbus/error.h"
#include "nimbus/render.h"
#include "scene/lights.h"
#include "support/estimate.h"
#include "support/scenes.h"
#include "support/stats.h"

namespace nimbus {
namespace {

using test::MeanAccumulator;
using test::scene_from_json;

// Mean and standard error of each channel of radiance(o, d) over n samples.
void expect_within_noise(const test::ChannelStats& s, const Rgb& exact, double rel_floor = 1e-9) {
  for (int k = 0; k < 3; ++k) {
    const double tol = 5.0 * s.c[k].stderr_mean() + rel_floor * std::abs(exact[k]) + 1e-12;
    EXPECT_NEAR(s.c[k].mean, exact[k], tol) << "channel " << k << " stderr " << s.c[k].stderr_mean();
  }
}

TEST(Tracking, MajorantGridSegmentsCoverTheRayInOrder) {
  const Scene scene = scene_from_json("{" + test::camera_json() + R"(,
    "media": [{"shape": {"type": "sphere", "center": [0.2, 0, 0], "radius": 1}, "sigma_s": 3},
              {"shape": {"type": "box", "min": [-2, -0.5, -0.5], "max": [-1, 0.5, 0.5]}, "sigma_s": 1}], "lights": []})");
  const SceneMedia media(scene.media);
  const MajorantGrid grid(media, 16);
  Rng rng(3, 4);
  for (int k = 0; k < 200; ++k) {
    const Vec3 o(-4 + 8 * rng.uniform(), -4 + 8 * rng.uniform(), -4 + 8 * rng.uniform());
    const Vec3 d = normalize(Vec3(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5));
    double last = -1.0, first = -1.0;
    bool ok = true;
    grid.traverse(o, d, 0.0, 100.0, [&](double t0, double t1, double maj) {
      if (first < 0) first = t0;
      if (last >= 0 && std::abs(t0 - last) > 1e-9) ok = false;
      if (!(t1 > t0)) ok = false;
      // The majorant bounds sigma_t at points inside the segment.
      for (int j = 1; j < 8; ++j) {
        const Vec3 p = o + d * (t0 + (t1 - t0) * j / 8.0);
        if (max_component(media.sigma_t(p)) > maj * (1 + 1e-6)) ok = false;
      }
      last = t1;
      return true;
    });
    EXPECT_TRUE(ok) << "ray " << k;
    double t0, t1;
    if (grid.bounds().intersect(o, d, 0.0, 100.0, &t0, &t1)) {
      EXPECT_NEAR(first, t0, 1e-9);
      EXPECT_NEAR(last, t1, 1e-9);
    }
  }
}

// Beer-Lambert: ratio tracking through a chromatic absorbing slab.
TEST(Tracking, RatioTrackingMatchesBeerLambertThroughASlab) {
  const Scene scene = scene_from_json("{" + test::camera_json() + R"(,
    "media": [{"shape": {"type": "box", "min": [-1, -0.3, -1], "max": [1, 0.4, 1]},
               "sigma_s": [0.2, 0.5, 1.0], "sigma_a": [0.5, 1.0, 2.0]},
              {"shape": {"type": "sphere", "center": [5, 0, 0], "radius": 0.5}, "sigma_s": 9}], "lights": []})");
  const SceneMedia media(scene.media);
  const MajorantGrid grid(media);
  const Vec3 o(0.1, -2, 0.2), d = normalize(Vec3(0.05, 1, -0.1));
  const double chord = 0.7 / d.y;
  MeanAccumulator acc[3];
  for (int i = 0; i < 100000; ++i) {
    Rng rng(9, i);
    const Rgb T = ratio_tracking_transmittance(media, grid, o, d, 10.0, rng);
    for (int k = 0; k < 3; ++k) acc[k].add(T[k]);
  }
  const Rgb sigma_t(0.7, 1.5, 3.0);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(acc[k].mean, std::exp(-sigma_t[k] * chord), 5 * acc[k].stderr_mean() + 1e-12);
  }
}

// Beer-Lambert seen by the camera: an absorbing slab in front of a uniform environment.
TEST(PathTracer, AbsorbingSlabTransmitsTheEnvironment) {
  const Scene scene = scene_from_json("{" + test::camera_json() + R"(,
    "media": [{"shape": {"type": "box", "min": [-1, -0.5, -1], "max": [1, 0.5, 1]},
               "sigma_s": 0, "sigma_a": [0.3, 1.0, 2.5]}],
    "lights": [{"type": "environment", "radiance": [1, 2, 3]}]})");
  const SceneContext ctx(scene);
  const PathTracer pt(ctx, 0);
  const Vec3 o(0, -3, 0), d = normalize(Vec3(0.2, 1, 0.1));
  const double chord = 1.0 / d.y;
  const auto s = test::estimate_li(pt, o, d, 20000);
  expect_within_noise(
      s, Rgb(1 * std::exp(-0.3 * chord), 2 * std::exp(-1.0 * chord), 3 * std::exp(-2.5 * chord)));
}

// The white furnace: an albedo-1 medium inside a uniform environment shows exactly the environment,
// for chromatic coefficients and overlapping media with different phase functions.
TEST(PathTracer, WhiteFurnaceShowsTheEnvironment) {
  const Scene scene = scene_from_json("{" + test::camera_json() + R"(,
    "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1},
               "sigma_s": [1.0, 3.0, 6.0], "phase": {"type": "hg", "g": 0.85}},
              {"shape": {"type": "box", "min": [-0.5, -0.5, -0.5], "max": [0.8, 0.5, 0.5]},
               "sigma_s": 2.0, "phase": {"type": "double_hg", "g1": 0.9, "g2": -0.3, "w": 0.8}}],
    "lights": [{"type": "environment", "radiance": [0.5, 1.0, 2.0]}]})");
  const SceneContext ctx(scene);
  const PathTracer pt(ctx, 0);
  for (const Vec3& d : {Vec3(0, 1, 0), normalize(Vec3(0.15, 1, -0.1))}) {
    const auto s = test::estimate_li(pt, Vec3(0, -4, 0), d, 20000);
    expect_within_noise(s, Rgb(0.5, 1.0, 2.0));
    for (int k = 0; k < 3; ++k) EXPECT_LT(s.c[k].stderr_mean(), 0.05 * 2.0);
  }
}

// With events truncated at K the furnace is dimmer than the environment and brightens with K.
TEST(PathTracer, TruncatedEventsApproachTheFurnaceFromBelow) {
  const Scene scene = scene_from_json("{" + test::camera_json() + R"(,
    "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": 4.0,
               "phase": {"type": "isotropic"}}],
    "lights": [{"type": "environment", "radiance": 1.0}]})");
  const SceneContext ctx(scene);
  double previous = 0.0;
  for (int k : {1, 2, 4, 8}) {
    const PathTracer pt(ctx, k);
    const auto s = test::estimate_li(pt, Vec3(0, -4, 0), Vec3(0, 1, 0), 20000);
    EXPECT_LT(s.c[0].mean, 1.0 - 3 * s.c[0].stderr_mean());
    EXPECT_GT(s.c[0].mean, previous + 3 * s.c[0].stderr_mean()) << "max_events " << k;
    previous = s.c[0].mean;
  }
}

// The wide-scatter tally (mfs validation): with f = 0 every scatter is wide, so at most K wide scatters
// is at most K events; with no limit reached it is the full radiance; the orders add up monotonically.
TEST(PathTracer, WideScatterLimitPartitionsTheRadiance) {
  const Scene scene = scene_from_json("{" + test::camera_json() + R"(,
    "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": 3.0, "sigma_a": 0.1,
               "phase": {"type": "hg", "g": 0.8}}],
    "lights": [{"type": "directional", "direction": [1, 0.3, -0.2], "irradiance": 1.0},
               {"type": "environment", "radiance": 0.3}]})");
  const SceneContext ctx(scene);
  const Vec3 o(0, -4, 0), d = normalize(Vec3(0.1, 1, 0.05));
  const int n = 40000;
  for (int K : {1, 2}) {
    PathTraceSettings wide;
    wide.max_wide_scatters = K;
    wide.peak_fraction = 0.0;
    const auto a = test::estimate_li(PathTracer(ctx, 0, wide), o, d, n),
               b = test::estimate_li(PathTracer(ctx, K), o, d, n, 2);
    const double tol = 5.0 * std::hypot(a.c[0].stderr_mean(), b.c[0].stderr_mean());
    EXPECT_NEAR(a.c[0].mean, b.c[0].mean, tol) << K;
  }
  PathTraceSettings all;
  all.max_wide_scatters = 1 << 20;
  const auto full = test::estimate_li(PathTracer(ctx, 0), o, d, n, 3),
             limited = test::estimate_li(PathTracer(ctx, 0, all), o, d, n, 4);
  EXPECT_NEAR(full.c[0].mean, limited.c[0].mean,
              5.0 * std::hypot(full.c[0].stderr_mean(), limited.c[0].stderr_mean()));
  double previous = 0.0;
  for (int K : {0, 1, 2, 4}) {
    PathTraceSettings w;
    w.max_wide_scatters = K;  // auto split (f = g^2)
    const auto s = test::estimate_li(PathTracer(ctx, 0, w), o, d, n, 5);
    EXPECT_GT(s.c[0].mean, previous) << K;
    EXPECT_LT(s.c[0].mean, full.c[0].mean + 5.0 * full.c[0].stderr_mean()) << K;
    previous = s.c[0].mean;
  }
  EXPECT_THROW(
      validate_integrator_options("pathtrace", nlohmann::json::parse(R"({"max_wide_scatters": -1})"), "t"),
      Error);
  EXPECT_NO_THROW(validate_integrator_options(
      "pathtrace", nlohmann::json::parse(R"({"max_wide_scatters": 2, "peak_fraction": "auto"})"), "t"));
}

// Chord of the unit sphere at the origin from p along w (p inside).
double exit_distance(const Vec3& p, const Vec3& w, double r) {
  const double b = dot(p, w), c = dot(p, p) - r * r;
  return -b + std::sqrt(std::max(0.0, b * b - c));
}

// Single scattering from a directional light, by an independent quadrature along the ray.
double single_scatter_quadrature(const Vec3& o, const Vec3& d, double r, double sigma_s, double sigma_t,
                                 const Phase& phase, const Vec3& light_dir, double E) {
  const double b = dot(o, d), c = dot(o, o) - r * r, disc = b * b - c;
  if (disc <= 0) return 0.0;
  const double t0 = -b - std::sqrt(disc), t1 = -b + std::sqrt(disc);
  const int n = 20000;
  double sum = 0.0;
  for (int i = 0; i < n; ++i) {
    const double t = t0 + (i + 0.5) * (t1 - t0) / n;
    const Vec3 p = o + d * t;
    const double s_light = exit_distance(p, -light_dir, r);
    sum += std::exp(-sigma_t * (t - t0)) * sigma_s * phase_eval(phase, dot(d, -light_dir)) * E *
           std::exp(-sigma_t * s_light);
  }
  return sum * (t1 - t0) / n;
}

TEST(PathTracer, SingleScatteringMatchesQuadrature) {
  const Scene scene = scene_from_json("{" + test::camera_json() + R"(,
    "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": 2.0,
               "sigma_a": 0.05, "phase": {"type": "hg", "g": 0.6}}],
    "lights": [{"type": "directional", "direction": [-0.354, 0.612, -0.707], "irradiance": 3.0}]})");
  const SceneContext ctx(scene);
  const PathTracer pt(ctx, 1);
  const Vec3 light_dir = normalize(Vec3(-0.354, 0.612, -0.707));
  for (const Vec3& d : {Vec3(0, 1, 0), normalize(Vec3(0.2, 1, 0.15)), normalize(Vec3(-0.1, 1, -0.12))}) {
    const Vec3 o(0, -4, 0);
    const double exact = single_scatter_quadrature(o, d, 1.0, 2.0, 2.05, HgPhase{0.6}, light_dir, 3.0);
    const auto s = test::estimate_li(pt, o, d, 40000);
    expect_within_noise(s, Rgb(exact), 1e-3);
    EXPECT_LT(s.c[0].stderr_mean(), 0.03 * exact);
  }
}

// A sun disc of small angular size converges to the delta light (difference ~ (radius)^2).
TEST(PathTracer, SmallSunDiscMatchesDeltaSun) {
  const std::string base = "{" + test::camera_json() + R"(,
    "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": 2.0,
               "phase": {"type": "hg", "g": 0.3}}],
    "lights": [{"type": "directional", "direction": [0, 1, -1], "irradiance": 2.0, "angular_diameter_deg": )";
  const Scene delta = scene_from_json(base + "0}]}");
  const Scene disc = scene_from_json(base + "0.53}]}");
  const SceneContext c1(delta), c2(disc);
  const PathTracer p1(c1, 1), p2(c2, 1);
  const auto s1 = test::estimate_li(p1, Vec3(0, -4, 0), Vec3(0, 1, 0), 30000, 5);
  const auto s2 = test::estimate_li(p2, Vec3(0, -4, 0), Vec3(0, 1, 0), 30000, 6);
  const double tol = 5 * std::hypot(s1.c[0].stderr_mean(), s2.c[0].stderr_mean());
  EXPECT_NEAR(s1.c[0].mean, s2.c[0].mean, tol);
}

// Point light single scattering against quadrature with 1/r^2 falloff.
TEST(PathTracer, PointLightSingleScatteringMatchesQuadrature) {
  const Scene scene = scene_from_json("{" + test::camera_json() + R"(,
    "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": 1.0,
               "sigma_a": 0.2, "phase": {"type": "isotropic"}}],
    "lights": [{"type": "point", "position": [0, 0, 3], "intensity": 5.0}]})");
  const SceneContext ctx(scene);
  const PathTracer pt(ctx, 1);
  const Vec3 o(0, -4, 0), d = normalize(Vec3(0.1, 1, 0.05)), light(0, 0, 3);
  const double b = dot(o, d), c = dot(o, o) - 1.0, t0 = -b - std::sqrt(b * b - c),
               t1 = -b + std::sqrt(b * b - c);
  double exact = 0.0;
  const int n = 20000;
  for (int i = 0; i < n; ++i) {
    const double t = t0 + (i + 0.5) * (t1 - t0) / n;
    const Vec3 p = o + d * t;
    const Vec3 w = normalize(light - p);
    exact += std::exp(-1.2 * (t - t0)) * 1.0 * kInv4Pi * 5.0 / (light - p).length2() *
             std::exp(-1.2 * exit_distance(p, w, 1.0));
  }
  exact *= (t1 - t0) / n;
  expect_within_noise(test::estimate_li(pt, o, d, 40000), Rgb(exact), 1e-3);
}

// The majorant grid against one global majorant (the naive tracker): same mean.
TEST(PathTracer, MajorantGridAgreesWithGlobalMajorant) {
  const Scene scene = scene_from_json("{" + test::camera_json() + R"(,
    "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": 3.0,
               "sigma_a": 0.1, "phase": {"type": "hg", "g": 0.7}},
              {"shape": {"type": "box", "min": [-1.5, -0.2, -0.2], "max": [1.5, 0.2, 0.2]}, "sigma_s": [2, 1, 0.5]}],
    "lights": [{"type": "directional", "direction": [0, 0.5, -1], "irradiance": 1.0},
               {"type": "environment", "radiance": [0.1, 0.2, 0.3]}]})");
  // Analytic media off: ratio tracking and delta tracking against the majorant grid's cells.
  SceneContext grid_ctx(scene, 24, false), global_ctx(scene, 0, true);
  ASSERT_TRUE(grid_ctx.analytic.active());
  grid_ctx.analytic = AnalyticMedia();
  global_ctx.analytic = AnalyticMedia();
  const PathTracer a(grid_ctx, 0), b(global_ctx, 0);
  for (const Vec3& d : {Vec3(0, 1, 0), normalize(Vec3(0.25, 1, 0.05))}) {
    const auto sa = test::estimate_li(a, Vec3(0, -4, 0), d, 20000, 1);
    const auto sb = test::estimate_li(b, Vec3(0, -4, 0), d, 20000, 2);
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(sa.c[k].mean, sb.c[k].mean, 5 * std::hypot(sa.c[k].stderr_mean(), sb.c[k].stderr_mean()));
    }
  }
}

// The analytic path (free flights over the shapes' exact pieces, closed-form transmittance for next-event
// estimation: media/analytic_media.h) against one global majorant with ratio tracking (the naive
// tracker), for overlapping chromatic media, a transform and an environment: same mean, and less noise.
TEST(PathTracer, AnalyticMediaAgreeWithGlobalMajorant) {
  const Scene scene = scene_from_json("{" + test::camera_json() + R"(,
    "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": 3.0,
               "sigma_a": 0.1, "phase": {"type": "hg", "g": 0.7}, "transform": {"scale": [1.2, 1, 0.8]}},
              {"shape": {"type": "box", "min": [-1.5, -0.2, -0.2], "max": [1.5, 0.2, 0.2]}, "sigma_s": [2, 1, 0.5]}],
    "lights": [{"type": "directional", "direction": [0, 0.5, -1], "irradiance": 1.0},
               {"type": "environment", "radiance": [0.1, 0.2, 0.3]}]})");
  SceneContext analytic_ctx(scene), global_ctx(scene, 0, true);
  ASSERT_TRUE(analytic_ctx.analytic.active());
  global_ctx.analytic = AnalyticMedia();
  const PathTracer a(analytic_ctx, 0), b(global_ctx, 0);
  for (const Vec3& d : {Vec3(0, 1, 0), normalize(Vec3(0.25, 1, 0.05)), normalize(Vec3(-0.1, 1, 0.12))}) {
    const auto sa = test::estimate_li(a, Vec3(0, -4, 0), d, 20000, 3);
    const auto sb = test::estimate_li(b, Vec3(0, -4, 0), d, 20000, 4);
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(sa.c[k].mean, sb.c[k].mean, 5 * std::hypot(sa.c[k].stderr_mean(), sb.c[k].stderr_mean()));
      EXPECT_LT(sa.c[k].stderr_mean(), sb.c[k].stderr_mean()) << "channel " << k;
    }
  }
}

TEST(Render, BitIdenticalForAnyThreadCount) {
  const Scene scene = scene_from_json("{" + test::camera_json(24, 16) + R"(,
    "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": 3.0,
               "phase": {"type": "hg", "g": 0.8}}],
    "lights": [{"type": "directional", "direction": [1, 1, -1], "irradiance": 1.0},
               {"type": "environment", "radiance": 0.2}],
    "integrator": {"type": "pathtrace", "spp": 4, "seed": 42}})");
  RenderOptions one, two;
  one.threads = 1;
  two.threads = 2;
  two.tile_size = 5;
  const RenderResult a = render(scene, one), b = render(scene, two);
  ASSERT_EQ(a.image.rgb.size(), b.image.rgb.size());
  EXPECT_EQ(0, std::memcmp(a.image.rgb.data(), b.image.rgb.data(), a.image.rgb.size() * sizeof(float)));
  EXPECT_FALSE(a.partial);
  EXPECT_EQ(a.nonfinite_samples, 0);
  RenderOptions reseeded = one;
  reseeded.seed = 43;
  const RenderResult c = render(scene, reseeded);
  EXPECT_NE(0, std::memcmp(a.image.rgb.data(), c.image.rgb.data(), a.image.rgb.size() * sizeof(float)));
}

TEST(Render, CancelledRenderIsPartial) {
  const Scene scene = scene_from_json("{" + test::camera_json(64, 64) + R"(,
    "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": 3.0}],
    "lights": [{"type": "environment", "radiance": 1}]})");
  std::atomic<bool> cancel{true};
  RenderOptions opt;
  opt.cancel = &cancel;
  const RenderResult r = render(scene, opt);
  EXPECT_TRUE(r.partial);
  EXPECT_EQ(r.spp, 0);  // cancelled before the first pass ended: no samples
  EXPECT_GT(r.spp_requested, 0);
}

}  // namespace
}  // namespace nimbus
