// `mfs` and `octave`: analytic limits of the phase split, the single-scattering limits of both
// integrators, option parsing and determinism. (Accuracy against pathtrace: validation/mfs_validation.py.)
#include <cstring>

#include <gtest/gtest.h>

#include "integrators/mfs.h"
#include "integrators/octave.h"
#include "integrators/single.h"
#include "nimbus/error.h"
#include "nimbus/render.h"
#include "support/scenes.h"
#include "support/stats.h"
#include "transport/phase_split.h"

namespace nimbus {
namespace {

// Integral over the sphere of a function of cos theta (midpoint rule in theta, dense near 0).
template <typename F>
double sphere_integral(F&& f) {
  const int n = 20000;
  double s = 0.0;
  for (int i = 0; i < n; ++i) {
    const double u0 = double(i) / n, u1 = double(i + 1) / n, um = 0.5 * (u0 + u1);
    const double th = kPi * um * um, dth = kPi * (u1 * u1 - u0 * u0);
    s += f(std::cos(th)) * std::sin(th) * dth;
  }
  return 2.0 * kPi * s;
}

TEST(PhaseSplit, PartsAreNormalisedAndRecombine) {
  for (const Phase& phase : {Phase(HgPhase{0.85}), Phase(DoubleHgPhase{0.9, -0.3, 0.8}), Phase(HgPhase{0.5})}) {
    const PhaseSplit split(phase, auto_peak_fraction(phase));
    const double f = split.f();
    EXPECT_NEAR(f, auto_peak_fraction(phase), 2e-3) << phase_describe(phase);
    EXPECT_NEAR(sphere_integral([&](double mu) { return split.wide(mu); }), 1.0, 2e-3);
    EXPECT_NEAR(sphere_integral([&](double mu) { return split.peak(mu); }), 1.0, 2e-3);
    for (double mu : {-0.9, 0.0, 0.5, 0.95, 0.999}) {
      EXPECT_NEAR(f * split.peak(mu) + (1 - f) * split.wide(mu), phase_eval(phase, mu), 1e-9 * phase_eval(phase, mu) + 1e-12);
      EXPECT_GE(split.peak(mu), 0.0);
      EXPECT_GE(split.wide(mu), 0.0);
    }
    // tau_p -> 0: the table reproduces the parts (no propagation yet).
    for (double mu : {-0.9, 0.0, 0.5, 0.9}) {
      EXPECT_NEAR(split.wide_eff(0.0, mu), split.wide(mu), 0.02 * split.wide(mu) + 1e-4) << mu;
      EXPECT_NEAR(split.peak_eff(0.0, mu), split.peak(mu), 0.02 * split.peak(mu) + 1e-3) << mu;
    }
    // Peak scatters conserve the light: each propagated part integrates to 1 at every depth.
    for (double tau : {0.3, 2.0, 10.0, 40.0}) {
      EXPECT_NEAR(sphere_integral([&](double mu) { return split.wide_eff(tau, mu); }), 1.0, 0.02) << tau;
      EXPECT_NEAR(sphere_integral([&](double mu) { return split.peak_eff(tau, mu); }), 1.0, 0.02) << tau;
    }
    // Propagation spreads the peak: less light straight ahead after more peak depth.
    EXPECT_LT(split.peak_eff(5.0, 1.0), split.peak_eff(0.5, 1.0));
  }
}

TEST(PhaseSplit, NoPeakIsThePhaseFunction) {
  const Phase phase = HgPhase{0.7};
  const PhaseSplit split(phase, 0.0);
  EXPECT_EQ(split.f(), 0.0);
  for (double tau : {0.0, 5.0})
    for (double mu : {-1.0, 0.0, 0.7, 0.99})
      EXPECT_NEAR(split.wide_eff(tau, mu), phase_eval(phase, mu), 0.01 * phase_eval(phase, mu)) << tau << " " << mu;
}

std::string sphere_scene(double sigma_s, double sigma_a, double g, bool env) {
  return "{" + test::camera_json() + R"(,
    "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": )" +
         std::to_string(sigma_s) + R"(, "sigma_a": )" + std::to_string(sigma_a) + R"(, "phase": {"type": "hg", "g": )" +
         std::to_string(g) + R"(}}],
    "lights": [{"type": "directional", "direction": [0.6, 1, -0.4], "irradiance": 2.0},
               {"type": "point", "position": [1.5, -2, 1], "intensity": 3.0})" +
         (env ? R"(, {"type": "environment", "radiance": [0.2, 0.3, 0.5]})" : "") + "]}";
}

// Mean radiance over a few camera rays.
template <typename I>
Rgb mean_radiance(const I& integrator, int n) {
  Rgb sum(0.0);
  int count = 0;
  for (const Vec3& d : {Vec3(0, 1, 0), normalize(Vec3(0.1, 1, 0.05)), normalize(Vec3(-0.15, 1, -0.12))}) {
    for (int i = 0; i < n; ++i) {
      Rng rng(7, i);
      sum += integrator.radiance(Vec3(0, -4, 0), d, rng);
      ++count;
    }
  }
  return sum / double(count);
}

TEST(Mfs, NoPeakAndBeerLambertIsSingleScattering) {
  const Scene scene = test::scene_from_json(sphere_scene(2.0, 0.1, 0.7, true));
  const SceneContext ctx(scene);
  MfsSettings ms;
  ms.peak_fraction = 0.0;
  ms.forward_light_path = false;
  ms.tau_step = 0.05;
  const MfsIntegrator mfs(ctx, ms);
  const SingleScatter single(ctx, SingleSettings{0.05, 1});
  const Rgb a = mean_radiance(mfs, 400), b = mean_radiance(single, 400);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(a[c], b[c], 0.02 * b[c]) << c;
}

TEST(Mfs, OpticallyThinMediumIsSingleScattering) {
  // Multiple scattering is O(tau) of single scattering: at tau = 0.01 mfs (any split) ~ single.
  const Scene scene = test::scene_from_json(sphere_scene(0.01, 0.0, 0.85, false));
  const SceneContext ctx(scene);
  MfsSettings ms;  // auto split, forward light path
  const MfsIntegrator mfs(ctx, ms);
  const SingleScatter single(ctx, SingleSettings{0.05, 1});
  const Rgb a = mean_radiance(mfs, 200), b = mean_radiance(single, 200);
  EXPECT_GT(a[0], b[0] * 0.999);  // never less than single scattering
  EXPECT_NEAR(a[0], b[0], 0.04 * b[0]);
}

TEST(Mfs, MoreThanSingleScatteringInDenseMedia) {
  const Scene scene = test::scene_from_json(sphere_scene(5.0, 0.05, 0.85, false));
  const SceneContext ctx(scene);
  const MfsIntegrator mfs(ctx, MfsSettings{});
  const SingleScatter single(ctx, SingleSettings{0.05, 1});
  EXPECT_GT(mean_radiance(mfs, 50)[0], 1.5 * mean_radiance(single, 50)[0]);
}

TEST(Octave, OneOctaveIsSingleScattering) {
  const Scene scene = test::scene_from_json(sphere_scene(2.0, 0.1, 0.7, true));
  const SceneContext ctx(scene);
  OctaveSettings os;
  os.octaves = 1;
  os.tau_step = 0.05;
  const OctaveIntegrator octave(ctx, os);
  const SingleScatter single(ctx, SingleSettings{0.05, 1});
  const Rgb a = mean_radiance(octave, 400), b = mean_radiance(single, 400);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(a[c], b[c], 0.03 * b[c]) << c;
  // More octaves add light.
  const OctaveIntegrator four(ctx, OctaveSettings{});
  EXPECT_GT(mean_radiance(four, 100)[0], 1.2 * a[0]);
}

TEST(Octave, ScalesEccentricity) {
  const Phase hg = scale_phase_eccentricity(HgPhase{0.8}, 0.5);
  EXPECT_NEAR(phase_mean_cosine(hg), 0.4, 1e-12);
  const Phase tab = scale_phase_eccentricity(GaussPhase(make_gauss_phase(0.05)), 0.5);
  EXPECT_NEAR(phase_mean_cosine(tab), 0.5 * phase_mean_cosine(GaussPhase(make_gauss_phase(0.05))), 2e-3);
}

TEST(Mfs, OptionsAreValidatedStrictly) {
  auto parse = [](const std::string& opts) {
    validate_integrator_options("mfs", nlohmann::json::parse(opts), "t.json");
  };
  EXPECT_NO_THROW(parse(R"({"tau_step": 0.2, "light_path": "beer_lambert", "propagator": "gaussian",
                            "peak_fraction": 0.8, "large_angle_scatters": 1, "shadow_map_resolution": 32})"));
  EXPECT_NO_THROW(parse(R"({"peak_fraction": "auto"})"));
  EXPECT_THROW(parse(R"({"tau_stpe": 0.2})"), Error);
  EXPECT_THROW(parse(R"({"light_path": "straight"})"), Error);
  EXPECT_THROW(parse(R"({"propagator": "exact"})"), Error);
  EXPECT_THROW(parse(R"({"peak_fraction": "half"})"), Error);
  EXPECT_THROW(parse(R"({"peak_fraction": 1.5})"), Error);
  EXPECT_THROW(parse(R"({"large_angle_scatters": 2})"), Error);
  EXPECT_NO_THROW(validate_integrator_options("octave", nlohmann::json::parse(R"({"octaves": 6, "a": 0.6, "b": 0.4, "c": 0.7})"), "t"));
  EXPECT_THROW(validate_integrator_options("octave", nlohmann::json::parse(R"({"octaves": 0})"), "t"), Error);
  EXPECT_THROW(validate_integrator_options("octave", nlohmann::json::parse(R"({"d": 0.5})"), "t"), Error);
  // Through the scene parser.
  EXPECT_THROW(test::scene_from_json("{" + test::camera_json() + R"(, "lights": [],
      "integrator": {"type": "mfs", "bogus": 1}})"), Error);
}

TEST(Mfs, BitIdenticalForAnyThreadCount) {
  for (const char* type : {"mfs", "octave"}) {
    const Scene scene = test::scene_from_json("{" + test::camera_json(16, 12) + R"(,
      "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": 3.0,
                 "phase": {"type": "hg", "g": 0.8}}],
      "lights": [{"type": "directional", "direction": [1, 1, -1], "irradiance": 1.0},
                 {"type": "environment", "radiance": 0.2}],
      "integrator": {"type": ")" + std::string(type) + R"(", "spp": 2, "seed": 42}})");
    RenderOptions one, two;
    one.threads = 1;
    two.threads = 2;
    two.tile_size = 5;
    const RenderResult a = render(scene, one), b = render(scene, two);
    ASSERT_EQ(a.image.rgb.size(), b.image.rgb.size());
    EXPECT_EQ(0, std::memcmp(a.image.rgb.data(), b.image.rgb.data(), a.image.rgb.size() * sizeof(float))) << type;
    EXPECT_EQ(a.nonfinite_samples, 0);
  }
}

}  // namespace
}  // namespace nimbus
