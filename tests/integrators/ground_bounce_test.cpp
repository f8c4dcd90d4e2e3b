// The light a diffuse ground reflects into a medium above it, as the scatter grid holds it
// (photon_tracer.h: emit_with_surfaces; ScatterPhotons::bounce). A thin, isotropic medium over a large
// ground: the grid's fluence at the medium's centre against the closed form (a sun, a uniform sky) or an
// independent quadrature over the ground (a point light, a spot). Photons aimed at the medium alone
// (emit) land only in its own shadow and miss nearly all of it.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "integrators/scatter_grid.h"
#include "scene/lights.h"
#include "support/scenes.h"
#include "transport/phase_split.h"

namespace nimbus {
namespace {

// The medium: a sphere of radius 0.5, sigma_s 0.005 (optical diameter 0.005), no absorption.
constexpr double kHeight = 2.0;  // of the medium's centre over the ground
constexpr double kHalf = 60.0;   // the ground's half size
constexpr double kAlbedo = 0.5;  // the ground's

Scene ground_scene(const std::string& light, const std::string& sigma_s = "0.005",
                   const std::string& albedo = "0.5") {
  return test::scene_from_json("{" + test::camera_json(8, 8, 40.0) + R"(,
    "media": [{"shape": {"type": "sphere", "center": [0, 0, 2], "radius": 0.5}, "sigma_s": )" +
                               sigma_s + R"(,
               "sigma_a": 0.0, "phase": {"type": "isotropic"}}],
    "surfaces": [{"shape": {"type": "rectangle", "center": [0, 0, 0], "normal": [0, 0, 1], "up": [0, 1, 0],
                  "size": [120, 120]}, "material": {"type": "diffuse", "albedo": )" +
                               albedo + R"(}}],
    "lights": [)" + light + "]}");
}

// The grid's fluence (integral of the radiance over directions) at the medium's centre, for `seed`.
Rgb grid_fluence_rgb(const SceneContext& ctx, uint64_t seed) {
  const Phase& phase = ctx.media.phase(0);
  const PhaseSplit split(phase, auto_peak_fraction(phase));
  ScatterGridSettings s;
  s.photons = 1 << 18;
  s.resolution = 8;
  s.seed = seed;
  const ScatterGrid grid(ctx, {&split}, {split.f()}, s);
  // An isotropic phase function's moments (1, 0, 0): the radiance scattered is the fluence / 4 pi.
  const std::array<Rgb, kShMaxBands> chi = {Rgb(1.0), Rgb(0.0), Rgb(0.0)};
  return grid.scattered(Vec3(0, 0, kHeight), Vec3(0, 0, 1), chi) * (4.0 * kPi);
}
double grid_fluence(const SceneContext& ctx, uint64_t seed) { return luminance(grid_fluence_rgb(ctx, seed)); }

// The solid angle of the ground (a kHalf square) from kHeight above its centre.
double ground_solid_angle() { return 4.0 * std::asin(kHalf * kHalf / (kHalf * kHalf + kHeight * kHeight)); }

// The fluence at the centre from the ground lit with irradiance E(rho) at distance rho from the point
// below it: the ground's radiance kAlbedo E / pi seen under dOmega = h dA / d^3 (midpoint rule in rho out
// to the ground's inscribed disc, then the corners' rest as at the disc's edge: under 0.1 %).
template <typename Irradiance>
double ground_fluence(Irradiance&& E) {
  constexpr int kSteps = 200000;
  double sum = 0.0;
  for (int i = 0; i < kSteps; ++i) {
    const double rho = kHalf * (i + 0.5) / kSteps, d2 = kHeight * kHeight + rho * rho;
    sum += kAlbedo * E(rho) / kPi * kHeight / (d2 * std::sqrt(d2)) * 2.0 * kPi * rho * (kHalf / kSteps);
  }
  return sum;
}

// Mean and standard error of the grid's fluence over seeds; checks them against `exact` plus the light
// the medium scatters itself (each light's photons are tallied after their first wide scatter, the
// sky's from their entry): sigma_s R times the fluence phi0 of the light that reaches it unscattered
// (integral over the sphere of sigma_s phi0 / (4 pi d^2), d from its centre), within 4 standard errors
// plus 1 % (the medium's shadow on the ground, under its optical diameter of 0.5 %).
void expect_fluence(const std::string& light, double exact, double phi0) {
  exact += 0.005 * 0.5 * phi0;
  const Scene scene = ground_scene(light);
  const SceneContext ctx(scene);
  constexpr int kSeeds = 8;
  double v[kSeeds], mean = 0.0, var = 0.0;
  for (int i = 0; i < kSeeds; ++i) mean += (v[i] = grid_fluence(ctx, uint64_t(i + 1))) / kSeeds;
  for (double x : v) var += (x - mean) * (x - mean) / (kSeeds - 1);
  const double se = std::sqrt(var / kSeeds);
  std::printf("%s: grid %.5f +- %.5f, exact %.5f\n", light.c_str(), mean, se, exact);
  EXPECT_LT(se, 0.03 * exact);
  EXPECT_NEAR(mean, exact, 4.0 * se + 0.01 * exact);
}

// A sun straight down: the ground's radiance kAlbedo E / pi in every direction of its solid angle.
TEST(GroundBounce, SunlitGroundLightsTheMediumAbove) {
  const double bounce = kAlbedo * 2.0 / kPi * ground_solid_angle();
  expect_fluence(R"({"type": "directional", "direction": [0, 0, -1], "irradiance": 2.0})", bounce,
                 2.0 + bounce);
}

// A chromatic medium over a coloured ground: the medium's photons walk with hero channels (ScatterPhotons'
// HeroWalk), which start with the far plane's weights too; each channel as the grey sun's, with that
// channel's albedo and scattering.
TEST(GroundBounce, ChromaticMediumOverAColouredGroundKeepsEachChannel) {
  const Scene scene = ground_scene(R"({"type": "directional", "direction": [0, 0, -1], "irradiance": 2.0})",
                                   "[0.004, 0.005, 0.006]", "[0.3, 0.5, 0.7]");
  const SceneContext ctx(scene);
  const Rgb albedo(0.3, 0.5, 0.7), sigma_s(0.004, 0.005, 0.006);
  constexpr int kSeeds = 8;
  Rgb v[kSeeds], mean(0.0), var(0.0);
  for (int i = 0; i < kSeeds; ++i) mean += (v[i] = grid_fluence_rgb(ctx, uint64_t(i + 1))) * (1.0 / kSeeds);
  for (const Rgb& x : v) var += (x - mean) * (x - mean) * (1.0 / (kSeeds - 1));
  for (int c = 0; c < 3; ++c) {
    const double bounce = albedo[c] * 2.0 / kPi * ground_solid_angle();
    const double exact = bounce + sigma_s[c] * 0.5 * (2.0 + bounce), se = std::sqrt(var[c] / kSeeds);
    std::printf("channel %d: grid %.5f +- %.5f, exact %.5f\n", c, mean[c], se, exact);
    EXPECT_LT(se, 0.03 * exact) << c;
    EXPECT_NEAR(mean[c], exact, 4.0 * se + 0.01 * exact) << c;
  }
}

// A uniform sky: its own light from every direction the ground leaves open (the environment's photons
// are tallied from their entry), and the ground's kAlbedo L from the rest.
TEST(GroundBounce, SkyAndTheGroundItLights) {
  const double omega = ground_solid_angle();
  const double phi = 0.1 * (4.0 * kPi - omega) + kAlbedo * 0.1 * omega;
  expect_fluence(R"({"type": "environment", "radiance": 0.1})", phi, phi);
}

// A point light above the medium, and a spot pointing down with a cone wider than the medium's: the
// ground's irradiance I f(theta) cos / d^2 by the quadrature (the spot's falloff f by scene/lights.h).
TEST(GroundBounce, PointAndSpotLightsLightTheGroundAroundTheMedium) {
  constexpr double kLight = 5.0;  // the lights' height
  const auto at = [&](double rho, double f) {
    const double d2 = kLight * kLight + rho * rho;
    return f * kLight / (d2 * std::sqrt(d2));
  };
  // The light straight on the medium: I / 3^2 (the spot's axis).
  const double point = ground_fluence([&](double rho) { return 4.0 * at(rho, 1.0); });
  expect_fluence(R"({"type": "point", "position": [0, 0, 5], "intensity": 4.0})", point, 4.0 / 9.0 + point);
  SpotLight spot;
  spot.direction = Vec3(0, 0, -1);
  spot.cone_angle_deg = 100.0;
  spot.blend = 0.2;
  const double spotted = ground_fluence([&](double rho) {
    return 4.0 * at(rho, spot_falloff(spot, kLight / std::sqrt(kLight * kLight + rho * rho)));
  });
  expect_fluence(R"({"type": "spot", "position": [0, 0, 5], "direction": [0, 0, -1], "intensity": 4.0,
                     "cone_angle_deg": 100, "blend": 0.2})",
                 spotted, 4.0 / 9.0 + spotted);
}

}  // namespace
}  // namespace nimbus
