// The spot, sphere and rectangle lights in the integrators, against independent quadratures: a spot's
// single scattering in a thin homogeneous box (single; pathtrace with one event), the light a diffuse
// point reflects from a sphere or rectangle light seen through an absorbing slab (pathtrace, single),
// and a visible light seen through an absorber by a camera ray (every integrator).
#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "integrators/mfs.h"
#include "integrators/octave.h"
#include "integrators/pathtrace.h"
#include "integrators/photon_tracer.h"
#include "integrators/single.h"
#include "media/analytic_media.h"
#include "support/scenes.h"
#include "support/stats.h"

namespace nimbus {
namespace {

// Mean and standard error of one channel of Li along one ray over n samples.
test::MeanAccumulator mean_li(const Integrator& integrator, const Ray& ray, int n, uint64_t seed = 1) {
  test::MeanAccumulator acc;
  for (int i = 0; i < n; ++i) {
    Rng rng(seed, i);
    acc.add(integrator.Li(ray, rng).x);
  }
  return acc;
}

double smoothstep_edge(double cone_deg, double blend, double cos_a) {
  const double ch = std::cos(cone_deg * kPi / 360.0);
  if (cos_a <= ch) return 0.0;
  if (blend == 0.0) return 1.0;
  const double x = std::min(1.0, (cos_a - ch) / (blend * (1.0 - ch)));
  return x * x * (3.0 - 2.0 * x);
}

// A spot above a homogeneous box [-1, 1]^3 (isotropic), a camera ray along +x at height z0 through
// the cone's edge. Exact single scattering: the integral over the ray of sigma_s / (4 pi) T_cam I f / d^2
// T_light, where the leg to the spot leaves the box through its top (z = 1): a share (1 - z0) / (2 - z0)
// of its length lies inside.
TEST(AreaLightsInIntegrators, SpotSingleScatterMatchesTheQuadrature) {
  const double sigma_s = 0.3, sigma_t = 0.4, I = 5.0, cone = 50.0, blend = 0.3;
  const Scene scene = test::scene_from_json("{" + test::camera_json() + R"(,
    "media": [{"shape": {"type": "box", "min": [-1, -1, -1], "max": [1, 1, 1]}, "sigma_s": 0.3, "sigma_a": 0.1}],
    "lights": [{"type": "spot", "position": [0, 0, 2], "direction": [0, 0, -1], "intensity": 5,
                "cone_angle_deg": 50, "blend": 0.3}]})");
  const SceneContext ctx(scene);
  const PathTracer pt(ctx, 1);
  const SingleScatter single(ctx, SingleSettings{0.02, 1});
  const SingleScatter single_map(ctx, SingleSettings{0.02, 1, Transmittance::shadow_map, 64});
  for (double z0 : {0.0, 0.4}) {
    const int m = 20000;
    double exact = 0.0;
    for (int k = 0; k < m; ++k) {
      const double s = 2.0 * (k + 0.5) / m;  // depth into the box
      const Vec3 x(-1.0 + s, 0.0, z0), to_spot = Vec3(0, 0, 2) - x;
      const double d = length(to_spot);
      const double f = smoothstep_edge(cone, blend, to_spot.z / d);
      exact += sigma_s / (4.0 * kPi) * std::exp(-sigma_t * s) * I * f / (d * d) *
               std::exp(-sigma_t * d * (1.0 - z0) / (2.0 - z0));
    }
    exact *= 2.0 / m;
    const Ray ray{Vec3(-3, 0, z0), Vec3(1, 0, 0)};
    const test::MeanAccumulator a = mean_li(single, ray, 2000), b = mean_li(pt, ray, 40000);
    EXPECT_NEAR(a.mean, exact, 5.0 * a.stderr_mean() + 0.003 * exact) << "single, z0 " << z0;
    EXPECT_NEAR(b.mean, exact, 5.0 * b.stderr_mean()) << "pathtrace, z0 " << z0;
    EXPECT_LT(b.stderr_mean(), 0.03 * exact);  // the test has power
    // With a shadow map, the spot reads the point light's map (its nodes march to the spot's position).
    const test::MeanAccumulator c = mean_li(single_map, ray, 2000);
    EXPECT_NEAR(c.mean, exact, 5.0 * c.stderr_mean() + 0.01 * exact) << "single (shadow map), z0 " << z0;
  }
}

// A sphere light (radius 0.5 at height 2.5) above the same box: single scattering along a ray at height
// z0 is the integral over the ray and over the light's cap of directions of sigma_s / (4 pi) T_cam L
// T_light, every leg to the light leaving the box through its top (checked).
TEST(AreaLightsInIntegrators, SphereLightSingleScatterMatchesTheQuadrature) {
  const double sigma_s = 0.3, sigma_t = 0.4, L = 6.0, r = 0.5;
  const Vec3 c(0, 0, 2.5);
  const Scene scene = test::scene_from_json("{" + test::camera_json() + R"(,
    "media": [{"shape": {"type": "box", "min": [-1, -1, -1], "max": [1, 1, 1]}, "sigma_s": 0.3, "sigma_a": 0.1}],
    "lights": [{"type": "sphere", "center": [0, 0, 2.5], "radius": 0.5, "radiance": 6}]})");
  const SceneContext ctx(scene);
  const PathTracer pt(ctx, 1);
  const SingleScatter single(ctx, SingleSettings{0.02, 1});
  const double z0 = 0.2;
  const int mt = 100, mc = 60;
  double exact = 0.0;
  for (int k = 0; k < mt; ++k) {
    const double s = 2.0 * (k + 0.5) / mt;
    const Vec3 x(-1.0 + s, 0.0, z0);
    const double d = length(c - x), cos_max = std::sqrt(1.0 - r * r / (d * d));
    double cap = 0.0;
    for (int i = 0; i < mc; ++i)
      for (int j = 0; j < mc; ++j) {
        const double ct = cos_max + (1.0 - cos_max) * (i + 0.5) / mc;
        const Vec3 w = spherical_direction(ct, 2.0 * kPi * (j + 0.5) / mc, (c - x) / d);
        const double len = (1.0 - z0) / w.z;
        const Vec3 exit = x + w * len;
        ASSERT_TRUE(std::abs(exit.x) <= 1.0 && std::abs(exit.y) <= 1.0);
        cap += L * std::exp(-sigma_t * len);
      }
    exact += sigma_s / (4.0 * kPi) * std::exp(-sigma_t * s) * cap * (1.0 - cos_max) * 2.0 * kPi / (mc * mc);
  }
  exact *= 2.0 / mt;
  const Ray ray{Vec3(-3, 0, z0), Vec3(1, 0, 0)};
  const test::MeanAccumulator a = mean_li(single, ray, 4000), b = mean_li(pt, ray, 40000);
  EXPECT_NEAR(a.mean, exact, 5.0 * a.stderr_mean() + 0.003 * exact) << "single";
  EXPECT_NEAR(b.mean, exact, 5.0 * b.stderr_mean()) << "pathtrace";
  EXPECT_LT(b.stderr_mean(), 0.03 * exact);
}

// A diffuse floor (z = 0, albedo 0.5) under an absorbing slab (0.5 < z < 1, sigma_a 1) and a light
// above it; the camera looks at the origin from beside the slab. The floor reflects (albedo / pi) times
// the transmittance-weighted irradiance E_T = int L cos T dw, T = exp(-0.5 / w_z).
Scene floor_scene(const std::string& light) {
  return test::scene_from_json("{" + test::camera_json() + R"(,
    "media": [{"shape": {"type": "box", "min": [-3, -3, 0.5], "max": [3, 3, 1]}, "sigma_s": 0, "sigma_a": 1}],
    "surfaces": [{"shape": {"type": "rectangle", "center": [0, 0, 0], "normal": [0, 0, 1], "up": [0, 1, 0],
                            "size": [6, 6]}, "material": {"type": "diffuse", "albedo": 0.5}}],
    "lights": [)" + light + "]}");
}

void expect_floor_matches(const Scene& scene, double exact) {
  const SceneContext ctx(scene);
  const Ray ray{Vec3(0, -3, 0.2), normalize(Vec3(0, 3, -0.2))};
  const PathTracer pt(ctx, 1);
  const SingleScatter single(ctx, SingleSettings{});
  const test::MeanAccumulator a = mean_li(pt, ray, 20000), b = mean_li(single, ray, 20000, 2);
  EXPECT_NEAR(a.mean, exact, 5.0 * a.stderr_mean()) << "pathtrace";
  EXPECT_NEAR(b.mean, exact, 5.0 * b.stderr_mean()) << "single";
  EXPECT_LT(a.stderr_mean(), 0.02 * exact);
  // With shadow maps, an area light's shadow is marched to a sampled point of it (no map): the same
  // answer up to the march's step error.
  const SingleScatter single_map(ctx, SingleSettings{0.1, 1, Transmittance::shadow_map, 64});
  const test::MeanAccumulator c = mean_li(single_map, ray, 20000, 3);
  EXPECT_NEAR(c.mean, exact, 5.0 * c.stderr_mean() + 0.005 * exact) << "single (shadow map)";
}

TEST(AreaLightsInIntegrators, SphereLightThroughAnAbsorberMatchesTheQuadrature) {
  const Vec3 c(0.3, 0.2, 2.5);
  const double r = 0.5, L = 4.0, d = length(c), cos_max = std::sqrt(1.0 - r * r / (d * d));
  // The cap of directions, 400 x 400 midpoints in (cos, phi) about the axis to the centre.
  const int m = 400;
  double E = 0.0, E_open = 0.0;
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) {
      const double ct = cos_max + (1.0 - cos_max) * (i + 0.5) / m;
      const Vec3 w = spherical_direction(ct, 2.0 * kPi * (j + 0.5) / m, c / d);
      E += L * w.z * std::exp(-0.5 / w.z);
      E_open += L * w.z;
    }
  E *= (1.0 - cos_max) * 2.0 * kPi / (double(m) * m);
  E_open *= (1.0 - cos_max) * 2.0 * kPi / (double(m) * m);
  EXPECT_NEAR(E_open, kPi * L * (r / d) * (r / d) * c.z / d, 1e-4 * E_open);  // the closed form
  expect_floor_matches(
      floor_scene(R"({"type": "sphere", "center": [0.3, 0.2, 2.5], "radius": 0.5, "radiance": 4})"),
      0.5 / kPi * E);
}

TEST(AreaLightsInIntegrators, RectangleLightThroughAnAbsorberMatchesTheQuadrature) {
  // A 1.2 x 0.8 rectangle at height 2, tilted, facing down; quadrature over its area.
  const Vec3 c(-0.2, 0.3, 2.0), n = normalize(Vec3(0.3, 0.0, -1.0)), up(0, 1, 0);
  const Vec3 ew = normalize(cross(n, up));
  const int m = 500;
  double E = 0.0;
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) {
      const Vec3 q = c + ew * (1.2 * ((i + 0.5) / m - 0.5)) + up * (0.8 * ((j + 0.5) / m - 0.5));
      const double dd = length(q);
      const Vec3 w = q / dd;
      E += 3.0 * w.z * std::max(0.0, -dot(w, n)) / (dd * dd) * std::exp(-0.5 / w.z);
    }
  E *= 1.2 * 0.8 / (double(m) * m);
  expect_floor_matches(floor_scene(R"({"type": "rectangle", "center": [-0.2, 0.3, 2], "normal": [0.3, 0, -1],
      "up": [0, 1, 0], "size": [1.2, 0.8], "radiance": 3})"),
                       0.5 / kPi * E);
}

TEST(AreaLightsInIntegrators, EveryIntegratorSeesAVisibleLightThroughTheMedium) {
  // A camera ray along +y meets the sphere light (radius 0.5 at y = 2) after 2 units of absorber.
  const Scene scene = test::scene_from_json("{" + test::camera_json() + R"(,
    "media": [{"shape": {"type": "box", "min": [-1, -1, -1], "max": [1, 1, 1]}, "sigma_s": 0, "sigma_a": 0.5}],
    "lights": [{"type": "sphere", "center": [0, 2.5, 0], "radius": 0.5, "radiance": 2, "visible": true},
               {"type": "rectangle", "center": [3, 0, 5], "normal": [0, 0, 1], "up": [0, 1, 0],
                "size": [1, 1], "radiance": 7, "visible": true}]})");
  const SceneContext ctx(scene);
  const Ray ray{Vec3(0, -3, 0), Vec3(0, 1, 0)};
  const double exact = 2.0 * std::exp(-1.0);
  const PathTracer pt(ctx, 0);
  const test::MeanAccumulator a = mean_li(pt, ray, 20000);
  EXPECT_NEAR(a.mean, exact, 5.0 * a.stderr_mean());
  const SingleScatter single(ctx, SingleSettings{});
  const test::MeanAccumulator b = mean_li(single, ray, 20000, 2);  // ratio tracking: unbiased, noisy
  EXPECT_NEAR(b.mean, exact, 5.0 * b.stderr_mean());
  EXPECT_LT(std::max(a.stderr_mean(), b.stderr_mean()), 0.02 * exact);
  const OctaveIntegrator octave(ctx, OctaveSettings{});
  EXPECT_NEAR(mean_li(octave, ray, 10).mean, exact, 0.01 * exact);
  MfsSettings ms;
  ms.photons = 1000;
  ms.beam_photons = 0;
  const MfsIntegrator mfs(ctx, ms);
  EXPECT_NEAR(mean_li(mfs, ray, 10).mean, exact, 0.01 * exact);
  // The rectangle's back faces the ray's way up: a ray going down sees it, one going up does not.
  const Ray down{Vec3(3, 0, 8), Vec3(0, 0, -1)}, up{Vec3(3, 0, 3), Vec3(0, 0, 1)};
  EXPECT_NEAR(mean_li(single, down, 10).mean, 7.0, 1e-12);
  EXPECT_EQ(mean_li(single, up, 10).mean, 0.0);
}

// In one constant-density sphere `mfs` takes the transmittance to a sampled point of an area light by
// the chord in closed form instead of marching it (half the CPU under the Cycles-comparison scenes' sphere
// and rectangle lights): the light through the medium the same as the march's (the scene without its
// closed form), within the noise and the march's midpoint error. The wide scatter K = 1 only, with
// straight beams (no photons, which would differ between the two walks).
TEST(AreaLightsInIntegrators, MfsTakesTheChordToAnAreaLightAsTheMarchDoes) {
  const Scene scene = test::scene_from_json("{" + test::camera_json() + R"(,
    "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": 2, "sigma_a": 0.2,
               "phase": {"type": "hg", "g": 0.7}}],
    "lights": [{"type": "sphere", "center": [0.5, 0.3, 2.2], "radius": 0.4, "radiance": 6},
               {"type": "rectangle", "center": [-2, 0, 0.5], "normal": [1, 0, -0.2], "up": [0, 1, 0],
                "size": [0.8, 0.6], "radiance": 5}]})");
  const SceneContext chord(scene);
  SceneContext marched(scene);
  ASSERT_TRUE(chord.analytic.active());
  marched.analytic = AnalyticMedia();  // no closed form: the majorant grid's march
  MfsSettings ms;
  ms.large_angle_scatters = 1;
  ms.beam_photons = 0;
  const MfsIntegrator a(chord, ms), b(marched, ms);
  for (const Ray& ray : {Ray{Vec3(0.2, -3, 0.1), Vec3(0, 1, 0)}, Ray{Vec3(-0.4, -3, 0.6), Vec3(0, 1, 0)}}) {
    const test::MeanAccumulator ma = mean_li(a, ray, 4000), mb = mean_li(b, ray, 4000);
    const double se = std::hypot(ma.stderr_mean(), mb.stderr_mean());
    ASSERT_GT(ma.mean, 0.0);
    EXPECT_NEAR(ma.mean, mb.mean, 5.0 * se + 0.01 * mb.mean);
    EXPECT_LT(se, 0.01 * mb.mean);
  }
}

// `mfs`'s photons from a spot aimed at the media's bounding sphere (off the spot's axis, so the aiming
// cone covers the blended edge and the outside): their summed power is I times the integral of the
// falloff over the aiming cone (a quadrature). Sphere and rectangle lights' photons leave their surface.
TEST(AreaLightsInIntegrators, PhotonsFromASpotCarryTheConesPower) {
  const Scene scene = test::scene_from_json("{" + test::camera_json() + R"(,
    "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": 1}],
    "lights": [{"type": "spot", "position": [-2.1131, 0, -4.5315], "direction": [0, 0, 1], "intensity": 3,
                "cone_angle_deg": 60, "blend": 0.5},
               {"type": "sphere", "center": [0, 0, 3], "radius": 0.5, "radiance": 2},
               {"type": "rectangle", "center": [0, 0, -3], "normal": [0, 0, 1], "up": [0, 1, 0],
                "size": [1, 2], "radiance": 2}]})");
  const SceneContext ctx(scene);
  const Vec3 spot(-2.1131, 0, -4.5315), c(0.0);
  const double d = length(c - spot), cos_max = std::sqrt(1.0 - 1.0 / (d * d));
  const int m = 1000;
  double exact = 0.0;
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) {
      const double ct = cos_max + (1.0 - cos_max) * (i + 0.5) / m;
      const Vec3 w = spherical_direction(ct, 2.0 * kPi * (j + 0.5) / m, (c - spot) / d);
      exact += 3.0 * smoothstep_edge(60.0, 0.5, w.z);
    }
  exact *= (1.0 - cos_max) * 2.0 * kPi / (double(m) * m);
  test::MeanAccumulator acc;
  const int n = 20000;
  for (int j = 0; j < n; ++j) {
    Rng rng(9, j);
    const Photon ph = emit(ctx, 0, c, 1.0, n, rng);
    acc.add(ph.power.x * n);
    EXPECT_EQ(ph.x, spot);
    Rng r1(10, j), r2(11, j);
    const Photon s = emit(ctx, 1, c, 1.0, n, r1), q = emit(ctx, 2, c, 1.0, n, r2);
    EXPECT_NEAR(length(s.x - Vec3(0, 0, 3)), 0.5, 1e-9);
    EXPECT_GT(dot(s.w, s.x - Vec3(0, 0, 3)), 0.0);
    EXPECT_NEAR(s.power.x * n, 2.0 * 4.0 * kPi * kPi * 0.25, 1e-9);
    EXPECT_NEAR(q.x.z, -3.0, 1e-12);
    EXPECT_GT(q.w.z, 0.0);
    EXPECT_NEAR(q.power.x * n, 2.0 * kPi * 2.0, 1e-9);
  }
  EXPECT_NEAR(acc.mean, exact, 5.0 * acc.stderr_mean());
  EXPECT_LT(acc.stderr_mean(), 0.01 * exact);
  EXPECT_LT(exact, 3.0 * 2.0 * kPi * (1.0 - cos_max) * 0.9);  // the edge cuts into the aiming cone

  // A spot narrower than the aiming cone sends its photons within its own cone: all of its power,
  // I times the integral of the falloff over the cone (a quadrature).
  const Scene narrow = test::scene_from_json("{" + test::camera_json() + R"(,
    "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": 1}],
    "lights": [{"type": "spot", "position": [0, 0, -3], "direction": [0.1, 0, 1], "intensity": 3,
                "cone_angle_deg": 20, "blend": 0.5}]})");
  const SceneContext ctx2(narrow);
  const Vec3 axis = normalize(Vec3(0.1, 0, 1));
  double all = 0.0;
  for (int i = 0; i < m; ++i) {
    const double ct = std::cos(10.0 * kPi / 180.0) + (1.0 - std::cos(10.0 * kPi / 180.0)) * (i + 0.5) / m;
    all += 3.0 * smoothstep_edge(20.0, 0.5, ct) * 2.0 * kPi * (1.0 - std::cos(10.0 * kPi / 180.0)) / m;
  }
  test::MeanAccumulator acc2;
  for (int j = 0; j < n; ++j) {
    Rng rng(12, j);
    const Photon ph = emit(ctx2, 0, c, 1.0, n, rng);
    acc2.add(ph.power.x * n);
    EXPECT_GT(dot(ph.w, axis), std::cos(10.0 * kPi / 180.0) - 1e-12);
  }
  EXPECT_NEAR(acc2.mean, all, 5.0 * acc2.stderr_mean());
  EXPECT_LT(acc2.stderr_mean(), 0.01 * all);
}

}  // namespace
}  // namespace nimbus
