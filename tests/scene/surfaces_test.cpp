// Surfaces: the Embree scene against closed forms (a sphere's roots, a box's slabs), and every integrator
// on scenes whose surface radiance has a closed form. Tolerances come from the estimated standard
// error of each Monte Carlo mean (5 sigma), never from stored results.
#include "scene/surfaces.h"

#include <gtest/gtest.h>

#include <cmath>

#include "integrators/registry.h"
#include "io/mesh.h"
#include "scene/context.h"
#include "support/scenes.h"
#include "support/stats.h"

namespace nimbus {
namespace {

using test::MeanAccumulator;
using test::scene_from_json;

Vec3 random_direction(Rng& rng) {
  return spherical_direction(1.0 - 2.0 * rng.uniform(), 2.0 * kPi * rng.uniform(), Vec3(0, 0, 1));
}

TEST(Surfaces, SphereHitsAreTheQuadraticsRoots) {
  const Vec3 c(0.3, -0.2, 0.1);
  const double r = 0.7;
  const SceneSurfaces surfaces({Surface{SphereSurface{c, r}, DiffuseMaterial{}}});
  Rng rng(1, 2);
  int hits = 0;
  for (int k = 0; k < 2000; ++k) {
    const Vec3 o = c + random_direction(rng) * 3.0;
    const Vec3 d = normalize(c + random_direction(rng) * 0.9 - o);
    // |o + t d - c|^2 = r^2: t^2 + 2 b t + q = 0.
    const double b = dot(o - c, d), q = dot(o - c, o - c) - r * r, disc = b * b - q;
    SurfaceHit hit;
    const bool found = surfaces.intersect(o, d, 1e30, &hit);
    ASSERT_EQ(found, disc > 0.0) << "ray " << k;
    EXPECT_EQ(surfaces.occluded(o, d, 1e30), found);
    if (!found) continue;
    ++hits;
    const double t = -b - std::sqrt(disc);
    EXPECT_NEAR(hit.t, t, 1e-5 * (1.0 + t));
    EXPECT_NEAR(dot(hit.ng, normalize(o + d * t - c)), 1.0, 1e-6);  // outward: faces the origin outside
    EXPECT_EQ(surfaces.occluded(o, d, 0.99 * t), false);
  }
  EXPECT_GT(hits, 500);
}

constexpr const char* kCubeObj = R"(v -0.5 -0.5 -0.5
v 0.5 -0.5 -0.5
v 0.5 0.5 -0.5
v -0.5 0.5 -0.5
v -0.5 -0.5 0.5
v 0.5 -0.5 0.5
v 0.5 0.5 0.5
v -0.5 0.5 0.5
f 1 4 3 2
f 5 6 7 8
f 1 2 6 5
f 3 4 8 7
f 2 3 7 6
f 1 5 8 4
)";

TEST(Surfaces, ACubeMeshEqualsTheAnalyticBox) {
  auto mesh = std::make_shared<const TriangleMesh>(mesh_from_obj_text(kCubeObj, "cube.obj"));
  ASSERT_EQ(mesh->triangle_count(), 12u);
  const SceneSurfaces from_mesh({Surface{MeshSurface{"cube.obj", mesh}, DiffuseMaterial{}}});
  const SceneSurfaces from_box({Surface{BoxSurface{Vec3(-0.5), Vec3(0.5)}, DiffuseMaterial{}}});
  Bounds slabs;
  slabs.extend(Vec3(-0.5));
  slabs.extend(Vec3(0.5));
  Rng rng(3, 4);
  int hits = 0;
  for (int k = 0; k < 2000; ++k) {
    const Vec3 o = random_direction(rng) * 2.5;
    const Vec3 d = normalize(random_direction(rng) * 0.8 - o);
    double t0, t1;
    const bool expected = slabs.intersect(o, d, 0.0, 1e30, &t0, &t1);
    SurfaceHit a, b;
    const bool ha = from_mesh.intersect(o, d, 1e30, &a), hb = from_box.intersect(o, d, 1e30, &b);
    // Rays through an edge may go either way in float; the slab test decides the rest.
    if (expected && t1 - t0 < 1e-4) continue;
    ASSERT_EQ(ha, expected) << "ray " << k;
    ASSERT_EQ(hb, expected) << "ray " << k;
    if (!expected) continue;
    ++hits;
    EXPECT_NEAR(a.t, t0, 1e-5);
    EXPECT_NEAR(b.t, t0, 1e-5);
    EXPECT_NEAR(dot(a.ng, b.ng), 1.0, 1e-6);
    EXPECT_LT(dot(a.ng, d), 0.0);
  }
  EXPECT_GT(hits, 500);
}

// The mean of Li along one ray over n samples, per channel.
std::array<MeanAccumulator, 3> surface_mean_radiance(const Scene& scene, const std::string& type,
                                                     const Ray& ray, int n,
                                                     std::vector<CameraSample>* samples = nullptr) {
  IntegratorSettings settings = scene.integrator;
  settings.type = type;
  settings.options = nlohmann::json::object();
  const SceneContext ctx(scene);
  const auto integrator = make_integrator(ctx, settings);
  std::array<MeanAccumulator, 3> m;
  for (int i = 0; i < n; ++i) {
    Rng rng(7, uint64_t(i));
    CameraSample cs;
    const Rgb L = integrator->Li(ray, rng, &cs);
    for (int c = 0; c < 3; ++c) m[c].add(L[c]);
    if (samples) samples->push_back(cs);
  }
  return m;
}

void expect_radiance(const std::array<MeanAccumulator, 3>& m, const Rgb& exact, const std::string& what) {
  for (int c = 0; c < 3; ++c) {
    const double tol = 5.0 * m[c].stderr_mean() + 1e-3 * exact[c] + 1e-12;
    EXPECT_NEAR(m[c].mean, exact[c], tol) << what << " channel " << c << " stderr " << m[c].stderr_mean();
    // The test has power: its noise is a small fraction of the answer.
    EXPECT_LT(m[c].stderr_mean(), 0.01 * exact[c]) << what << " channel " << c;
  }
}

const char* kSurfaceIntegrators[] = {"pathtrace", "single", "octave", "mfs"};
int samples_for(const std::string& type) { return type == "pathtrace" ? 80000 : 16000; }

// A diffuse ground under an absorbing slab, lit by a sun: the radiance of a ground point seen through
// the slab is (albedo / pi) E cos(theta_sun) exp(-sigma_a h / cos(theta_sun)) exp(-sigma_a h / cos(theta_view)).
TEST(SurfaceLight, DiffuseGroundUnderAnAbsorbingSlabIsExact) {
  const Scene scene = scene_from_json("{" + test::camera_json() + R"(,
    "media": [{"shape": {"type": "box", "min": [-50, -50, 0.2], "max": [50, 50, 1.2]}, "sigma_s": 0,
               "sigma_a": [0.8, 0.5, 0.2]}],
    "surfaces": [{"shape": {"type": "rectangle", "center": [0, 0, 0], "normal": [0, 0, 1], "up": [0, 1, 0],
                            "size": [200, 200]}, "material": {"type": "diffuse", "albedo": [0.7, 0.5, 0.3]}}],
    "lights": [{"type": "directional", "direction": [0.3, 0.2, -1], "irradiance": 2}]})");
  const Vec3 sun = normalize(Vec3(0.3, 0.2, -1)), o(0.1, -3, 3), target(0.2, 0.1, 0);
  const Vec3 d = normalize(target - o);
  const double cos_sun = -sun.z, cos_view = -d.z;
  const Rgb sigma_a(0.8, 0.5, 0.2), albedo(0.7, 0.5, 0.3);
  Rgb exact;
  for (int c = 0; c < 3; ++c)
    exact[c] = albedo[c] / kPi * 2.0 * cos_sun * std::exp(-sigma_a[c] * (1.0 / cos_sun + 1.0 / cos_view));
  for (const std::string type : kSurfaceIntegrators) {
    std::vector<CameraSample> cs;
    expect_radiance(surface_mean_radiance(scene, type, {o, d}, samples_for(type), &cs), exact, type);
    EXPECT_NEAR(cs[0].depth, length(target - o), 1e-5) << type;
    EXPECT_EQ(cs[0].escape_transmittance, Rgb(0.0)) << type;
    EXPECT_EQ(cs[0].albedo, albedo) << type;
  }
}

// A diffuse sphere inside an absorbing box, lit by a sun: the light and camera legs' lengths inside the
// box come from the geometry alone.
TEST(SurfaceLight, DiffuseSphereInsideAnAbsorbingMediumIsExact) {
  const Scene scene = scene_from_json("{" + test::camera_json() + R"(,
    "media": [{"shape": {"type": "box", "min": [-2, -2, -2], "max": [2, 2, 2]}, "sigma_s": 0, "sigma_a": 0.4}],
    "surfaces": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 0.5},
                  "material": {"type": "diffuse", "albedo": 0.6}}],
    "lights": [{"type": "directional", "direction": [0.2, 0.6, -1], "irradiance": 3}]})");
  const Vec3 sun = normalize(Vec3(0.2, 0.6, -1)), o(0.1, -5, 0.4);
  const Vec3 d = normalize(Vec3(0.05, 0, 0.25) - o);
  // The sphere's near root, its normal, the distance to the box's top or sides towards the sun.
  const double b = dot(o, d), t = -b - std::sqrt(b * b - (dot(o, o) - 0.25));
  const Vec3 p = o + d * t, n = p / 0.5, l = -sun;
  double to_box = 1e30;
  for (int a = 0; a < 3; ++a)
    if (l[a] != 0.0) to_box = std::min(to_box, ((l[a] > 0 ? 2.0 : -2.0) - p[a]) / l[a]);
  const double camera_leg = t - (-2.0 - o.y) / d.y;  // from the box's face y = -2 to the sphere
  ASSERT_GT(dot(n, l), 0.1);
  const double exact = 0.6 / kPi * 3.0 * dot(n, l) * std::exp(-0.4 * (to_box + camera_leg));
  for (const std::string type : kSurfaceIntegrators)
    expect_radiance(surface_mean_radiance(scene, type, {o, d}, samples_for(type)), Rgb(exact), type);
}

// A holdout is black with zero alpha behind what lies in front of it: the camera ray's transmittance to it.
TEST(SurfaceLight, AHoldoutIsBlackAndRecordsTheTransmittanceToIt) {
  const Scene scene = scene_from_json("{" + test::camera_json() + R"(,
    "media": [{"shape": {"type": "box", "min": [-1, -1.5, -1], "max": [1, -1, 1]}, "sigma_s": 0, "sigma_a": 0.9}],
    "surfaces": [{"shape": {"type": "box", "min": [-1, -0.5, -1], "max": [1, 0.5, 1]}, "material": {"type": "holdout"}}],
    "lights": [{"type": "directional", "direction": [0, 1, -1], "irradiance": 3},
               {"type": "environment", "radiance": 0.5}]})");
  const Ray ray{Vec3(0, -5, 0), Vec3(0, 1, 0)};
  for (const std::string type : kSurfaceIntegrators) {
    std::vector<CameraSample> cs;
    const auto m = surface_mean_radiance(scene, type, ray, samples_for(type) / 10, &cs);
    MeanAccumulator holdout;
    for (const CameraSample& s : cs) {
      holdout.add(s.holdout_transmittance[0]);
      EXPECT_EQ(s.escape_transmittance, Rgb(0.0));
      EXPECT_NEAR(s.depth, 4.5, 1e-5);
    }
    for (int c = 0; c < 3; ++c) EXPECT_EQ(m[c].mean, 0.0) << type;
    EXPECT_NEAR(holdout.mean, std::exp(-0.45), 5.0 * holdout.stderr_mean() + 1e-3) << type;
  }
}

// An opaque roof over a scattering slab, no sky: nothing lights the slab, in any integrator (mfs's
// photons included: they reflect off the roof's top, back to the sky).
TEST(SurfaceLight, ARoofShadowsTheMediumCompletely) {
  const Scene scene = scene_from_json("{" + test::camera_json() + R"(,
    "media": [{"shape": {"type": "box", "min": [-3, -3, -0.5], "max": [3, 3, 0.5]}, "sigma_s": 2,
               "phase": {"type": "hg", "g": 0.8}}],
    "surfaces": [{"shape": {"type": "rectangle", "center": [0, 0, 1], "normal": [0, 0, 1], "up": [0, 1, 0],
                            "size": [100, 100]}, "material": {"type": "diffuse", "albedo": 0.9}}],
    "lights": [{"type": "directional", "direction": [0.1, 0.2, -1], "irradiance": 5},
               {"type": "point", "position": [0, 0, 3], "intensity": 4}]})");
  Rng dirs(5, 6);
  for (const std::string type : kSurfaceIntegrators) {
    for (int k = 0; k < 4; ++k) {
      const Vec3 d = normalize(Vec3(dirs.uniform() - 0.5, 4.0, dirs.uniform() - 0.7));
      const auto m = surface_mean_radiance(scene, type, {Vec3(0, -5, 0), d}, 200);
      for (int c = 0; c < 3; ++c) EXPECT_EQ(m[c].mean, 0.0) << type << " ray " << k;
    }
  }
}

// A sunlit ground beside a wall the sun only grazes: the ground at the wall's foot is lit by the sun and
// by the wall, which the ground lights. mfs's surface gathers two bounces (kSurfaceBounces in mfs.cpp),
// so it has the ground -> wall -> ground light that one gather (the wall's direct light: none) misses,
// about 6 % of the ground's radiance there. What it still leaves out goes round once more (ground, wall,
// ground, wall: albedo^2 times the wall's view factor squared, ~0.4 %): mfs against pathtrace within 5
// standard errors plus 1 %.
TEST(SurfaceLight, MfsGathersLightThatGoesBetweenSurfacesTwice) {
  const Scene scene = scene_from_json("{" + test::camera_json() + R"(, "media": [],
    "surfaces": [{"shape": {"type": "rectangle", "center": [0, 0, 0], "normal": [0, 0, 1], "up": [0, 1, 0],
                            "size": [40, 40]}, "material": {"type": "diffuse", "albedo": 0.5}},
                 {"shape": {"type": "rectangle", "center": [0, 0, 2], "normal": [1, 0, 0], "up": [0, 0, 1],
                            "size": [40, 4]}, "material": {"type": "diffuse", "albedo": 0.5}}],
    "lights": [{"type": "directional", "direction": [0, 0, -1], "irradiance": 2}]})");
  const Vec3 o(3, 0.1, 2), target(0.3, 0, 0);
  const Ray ray{o, normalize(target - o)};
  const auto pt = surface_mean_radiance(scene, "pathtrace", ray, 80000);
  const auto mfs = surface_mean_radiance(scene, "mfs", ray, 16000);
  const double direct = 0.5 / kPi * 2.0;  // the sun alone
  for (int c = 0; c < 3; ++c) {
    const double se = std::hypot(pt[c].stderr_mean(), mfs[c].stderr_mean());
    EXPECT_NEAR(mfs[c].mean, pt[c].mean, 5.0 * se + 0.01 * pt[c].mean) << "channel " << c;
    // The wall's light is there to be missed (the test's power): well above the tolerance.
    EXPECT_GT(pt[c].mean - direct, 0.04 * pt[c].mean) << "channel " << c;
    EXPECT_LT(5.0 * se, 0.01 * pt[c].mean) << "channel " << c;
  }
}

}  // namespace
}  // namespace nimbus

namespace nimbus {
namespace {

// A transformed surface is the shape carried into the world: an ellipsoid from a sphere under
// non-uniform scale, a box under a rotation, a mesh with it.
TEST(Surfaces, TransformsCarryShapesIntoTheWorld) {
  const Transform xf = Transform::scaling(Vec3(1.0, 2.0, 0.5))
                           .then(Transform::rotation(Vec3(0, 0, 1), 30.0))
                           .then(Transform::translation(Vec3(0.5, -0.25, 1.0)));
  Surface ellipsoid{SphereSurface{Vec3(0.1, 0, 0), 0.8}, DiffuseMaterial{}};
  ellipsoid.transform = xf;
  Surface box{BoxSurface{Vec3(-0.5), Vec3(0.5)}, DiffuseMaterial{}};
  box.transform = xf;
  Surface cube{
      MeshSurface{"cube.obj", std::make_shared<const TriangleMesh>(mesh_from_obj_text(kCubeObj, "cube.obj"))},
      DiffuseMaterial{}};
  cube.transform = xf;
  const SceneSurfaces e({ellipsoid}), b({box}), m({cube});
  const Transform to_local = xf.inverse();
  Bounds slabs;
  slabs.extend(Vec3(-0.5));
  slabs.extend(Vec3(0.5));
  Rng rng(8, 9);
  int hits = 0;
  for (int k = 0; k < 2000; ++k) {
    const Vec3 o = Vec3(0.5, -0.25, 1.0) + random_direction(rng) * 4.0;
    const Vec3 d = normalize(Vec3(0.5, -0.25, 1.0) + random_direction(rng) * 1.2 - o);
    // In the shapes' own space the ray is o' + t d' with the same t.
    const Vec3 lo = to_local.point(o), ld = to_local.vector(d);
    const Vec3 oc = lo - Vec3(0.1, 0, 0);
    const double qa = dot(ld, ld), qb = dot(oc, ld), qc = dot(oc, oc) - 0.64, disc = qb * qb - qa * qc;
    SurfaceHit h;
    ASSERT_EQ(e.intersect(o, d, 1e30, &h), disc > 0.0) << "ray " << k;
    if (disc > 0.0) {
      const double t = (-qb - std::sqrt(disc)) / qa;
      EXPECT_NEAR(h.t, t, 1e-5 * (1.0 + t));
      // The world normal is the inverse transpose of the local one.
      const Vec3 n = normalize(xf.normal(lo + ld * t - Vec3(0.1, 0, 0)));
      EXPECT_NEAR(std::abs(dot(h.ng, n)), 1.0, 1e-6);
      ++hits;
    }
    double t0, t1;
    const bool in_box = slabs.intersect(lo, ld, 0.0, 1e30, &t0, &t1);
    if (in_box && t1 - t0 < 1e-4) continue;  // grazing an edge: either answer
    SurfaceHit hb, hm;
    ASSERT_EQ(b.intersect(o, d, 1e30, &hb), in_box) << "ray " << k;
    ASSERT_EQ(m.intersect(o, d, 1e30, &hm), in_box) << "ray " << k;
    if (!in_box) continue;
    EXPECT_NEAR(hb.t, t0, 1e-5 * (1.0 + t0));
    EXPECT_NEAR(hm.t, t0, 1e-5 * (1.0 + t0));
  }
  EXPECT_GT(hits, 300);
}

}  // namespace
}  // namespace nimbus
