// Emission in media, through every integrator: the closed form of the emission-absorption integral, a
// furnace with emission, black-body emission from a temperature grid, and bad input.
#include <gtest/gtest.h>
#include <nanovdb/util/GridBuilder.h>
#include <nanovdb/util/IO.h>

#include <cmath>

#include "integrators/pathtrace.h"
#include "integrators/registry.h"
#include "media/blackbody.h"
#include "nimbus/error.h"
#include "scene/context.h"
#include "support/estimate.h"
#include "support/scenes.h"
#include "support/scratch_dir.h"
#include "support/stats.h"

namespace nimbus {
namespace {

using test::MeanAccumulator;
using test::scene_from_json;

// mfs with fewer photons than its default (fast tests).
std::unique_ptr<Integrator> make(const SceneContext& ctx, const std::string& type, int photons = 1 << 15) {
  IntegratorSettings s;
  s.type = type;
  if (type == "mfs") s.options = {{"photons", photons}};
  return make_integrator(ctx, s);
}

// (j / sigma_a) (1 - exp(-sigma_a L)) per channel.
Rgb emission_absorption(const Rgb& j, const Rgb& sigma_a, double L) {
  Rgb out;
  for (int k = 0; k < 3; ++k) out[k] = j[k] / sigma_a[k] * (1.0 - std::exp(-sigma_a[k] * L));
  return out;
}

const Rgb kJ(1.0, 2.0, 3.0), kSigmaA(0.5, 1.0, 4.0);

// A purely emitting and absorbing slab (box, 1 thick along y) and sphere (radius 1, 2 thick through its
// centre): every integrator against the closed form, pathtrace within its noise.
TEST(Emission, EmissionAbsorptionClosedFormEveryIntegrator) {
  const std::string medium = R"("sigma_s": 0, "sigma_a": [0.5, 1.0, 4.0], "emission": [1, 2, 3]}])";
  const std::pair<std::string, double> shapes[] = {
      {R"({"shape": {"type": "box", "min": [-2, -0.5, -2], "max": [2, 0.5, 2]}, )", 1.0},
      {R"({"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, )", 2.0}};
  for (const auto& [shape, L] : shapes) {
    const Scene scene =
        scene_from_json("{" + test::camera_json() + R"(, "lights": [], "media": [)" + shape + medium + "}");
    const SceneContext ctx(scene);
    const Rgb exact = emission_absorption(kJ, kSigmaA, L);
    const Vec3 o(0, -4, 0), d(0, 1, 0);
    const auto pt = test::estimate_li(*make(ctx, "pathtrace"), o, d, 20000);
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(pt.c[k].mean, exact[k], 5.0 * pt.c[k].stderr_mean() + 1e-12) << shape << k;
      EXPECT_LT(pt.c[k].stderr_mean(), 0.02 * exact[k]);  // the test has the power to see a 10% error
    }
    for (const char* type : {"single", "octave", "mfs"}) {
      const auto s = test::estimate_li(*make(ctx, type), o, d, 8);
      for (int k = 0; k < 3; ++k)
        EXPECT_NEAR(s.c[k].mean, exact[k], 1e-3 * exact[k]) << type << " " << L << k;
    }
  }
}

// A transparent emitter (no extinction at all): the radiance is j L, and the majorant's floor for emitting
// cells lets the trackers see it.
TEST(Emission, TransparentEmitterIsSeen) {
  const Scene scene = scene_from_json("{" + test::camera_json() + R"(, "lights": [], "media": [
      {"shape": {"type": "box", "min": [-2, -0.75, -2], "max": [2, 0.75, 2]}, "sigma_s": 0, "emission": 0.4}]})");
  const SceneContext ctx(scene);
  const Vec3 o(0, -4, 0), d(0, 1, 0);
  const auto pt = test::estimate_li(*make(ctx, "pathtrace"), o, d, 4000);
  EXPECT_NEAR(pt.c[0].mean, 0.6, 5.0 * pt.c[0].stderr_mean() + 1e-12);
  EXPECT_LT(pt.c[0].stderr_mean(), 0.02 * 0.6);
  for (const char* type : {"single", "octave", "mfs"})
    EXPECT_NEAR(test::estimate_li(*make(ctx, type), o, d, 4).c[0].mean, 0.6, 1e-5) << type;
}

// A furnace with emission: deep inside a large scattering and absorbing sphere with uniform emission j the
// radiance is j / sigma_a in every direction (the emitted light scattered any number of times). pathtrace
// within its noise; mfs (emitted photons in its scatter grid) within a few percent.
TEST(Emission, FurnaceWithEmission) {
  const Scene scene = scene_from_json("{" + test::camera_json() + R"(, "lights": [], "media": [
      {"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 4}, "sigma_s": 4.0, "sigma_a": 1.0,
       "emission": [1.0, 0.5, 0.25]}]})");
  const SceneContext ctx(scene);
  const Rgb exact(1.0, 0.5, 0.25);  // the diffusion length 1 / sqrt(3 sigma_a sigma_t) is 1/15 of the radius
  const Vec3 o(0, 0, 0), d = normalize(Vec3(0.3, 1, 0.2));
  const auto pt = test::estimate_li(*make(ctx, "pathtrace"), o, d, 4000);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(pt.c[k].mean, exact[k], 5.0 * pt.c[k].stderr_mean() + 1e-9 * exact[k]) << k;
    EXPECT_LT(pt.c[k].stderr_mean(), 0.03 * exact[k]);
  }
  // mfs: its scatter grid's photon noise at one point is several per cent with 2^17 photons (3.7 % at one
  // point with 2^20), so average 27 points of the core (at least 35 diffusion lengths from the edge).
  const auto mfs_integrator = make(ctx, "mfs", 1 << 17);
  Rgb mean(0.0);
  for (int k = 0; k < 27; ++k) {
    const Vec3 p(k % 3 - 1.0, k / 3 % 3 - 1.0, k / 9 - 1.0);
    const auto s = test::estimate_li(*mfs_integrator, p * 0.8, d, 1, uint64_t(k));
    for (int c = 0; c < 3; ++c) mean[c] += s.c[c].mean / 27.0;
  }
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(mean[k], exact[k], 0.05 * exact[k]) << k;
}

// Writes density (1 in index box [0, 15]^3, voxel 0.1, centred on the origin) and temperature (T0 in a
// larger box, voxel 0.05: another voxel size) to one .nvdb file.
void write_fire(const std::filesystem::path& file, float T0) {
  std::vector<nanovdb::GridHandle<nanovdb::HostBuffer>> handles;
  nanovdb::GridBuilder<float> density(0.0f, nanovdb::GridClass::FogVolume);
  density([](const nanovdb::Coord&) { return 1.0f; }, nanovdb::CoordBBox({0, 0, 0}, {15, 15, 15}));
  handles.push_back(density.getHandle<>(0.1, nanovdb::Vec3d(-0.75), "density"));
  nanovdb::GridBuilder<float> temperature(0.0f, nanovdb::GridClass::FogVolume);
  temperature([&](const nanovdb::Coord&) { return T0; }, nanovdb::CoordBBox({0, 0, 0}, {39, 39, 39}));
  handles.push_back(temperature.getHandle<>(0.05, nanovdb::Vec3d(-0.975), "temperature"));
  nanovdb::io::writeGrids(file.string(), handles);
}

std::string fire_medium(const std::filesystem::path& file, const std::string& extra,
                        const std::string& grid = "temperature") {
  return R"("media": [{"shape": {"type": "vdb", "file": ")" + file.string() +
         R"(", "grid": "density"}, "sigma_s": 0, "sigma_a": [0.5, 1.0, 2.0], "temperature_grid": ")" + grid +
         "\"" + extra + "}]";
}

// Black-body emission from a temperature grid with constant temperature where there is density: the
// radiance is intensity B_rgb(T) (1 - exp(-tau)), tau = sigma_a x the density's integral along the ray.
TEST(Emission, BlackbodyFromTemperatureGrid) {
  test::ScratchDir dir("emission_fire");
  write_fire(dir / "fire.nvdb", 15.0f);  // 15 x 100 + 500 = 2000 K
  const Scene scene = scene_from_json("{" + test::camera_json() + R"(, "lights": [], )" +
                                      fire_medium(dir / "fire.nvdb", R"(, "temperature_scale": 100,
      "temperature_offset": 500, "intensity": 1e-4)") +
                                      "}");
  const SceneContext ctx(scene);
  const Vec3 o(0.01, -4, 0.02), d(0, 1, 0);  // through voxel 7.6 of 0 .. 15: 16 voxels of density 1
  const Rgb B = blackbody_rgb(2000.0) * 1e-4;
  // The density's integral along the ray: 15 voxels between the first and last centre plus two half-voxel
  // ramps of the trilinear fall-off, 16 voxels of 0.1.
  const Rgb sigma_a(0.5, 1.0, 2.0);
  Rgb exact;
  for (int k = 0; k < 3; ++k) exact[k] = B[k] * (1.0 - std::exp(-sigma_a[k] * 1.6));
  const auto pt = test::estimate_li(*make(ctx, "pathtrace"), o, d, 20000);
  for (int k = 0; k < 2; ++k) {  // blue is clamped to 0 at 2000 K
    EXPECT_NEAR(pt.c[k].mean, exact[k], 5.0 * pt.c[k].stderr_mean()) << k;
    EXPECT_LT(pt.c[k].stderr_mean(), 0.02 * exact[k]);
  }
  for (const char* type : {"single", "octave", "mfs"}) {
    const auto s = test::estimate_li(*make(ctx, type), o, d, 8);
    // mfs's steps grow with depth (its step_growth), so the density's ramps are sampled more coarsely.
    const double tol = std::string(type) == "mfs" ? 5e-3 : 1e-3;
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(s.c[k].mean, exact[k], tol * exact[0]) << type << k;
  }
}

// An emission grid scales the constant emission in place of the density, and may reach beyond the
// density grid: here a grid of 1 (voxel 0.05, 40 voxels across) with no extinction at all, so L = j times
// the grid's integral along the ray, 2 x 40 x 0.05 = 4 (39 voxel spans plus two half-voxel ramps).
TEST(Emission, EmissionGridBeyondTheDensity) {
  test::ScratchDir dir("emission_grid");
  write_fire(dir / "fire.nvdb", 1.0f);
  const Scene scene = scene_from_json("{" + test::camera_json() + R"(, "lights": [], "media": [
      {"shape": {"type": "vdb", "file": ")" +
                                      (dir / "fire.nvdb").string() + R"(", "grid": "density"},
       "sigma_s": 0, "emission": 2, "emission_grid": "temperature"}]})");
  const SceneContext ctx(scene);
  const Vec3 o(0.01, -4, 0.02), d(0, 1, 0);
  const auto pt = test::estimate_li(*make(ctx, "pathtrace"), o, d, 4000);
  EXPECT_NEAR(pt.c[0].mean, 4.0, 5.0 * pt.c[0].stderr_mean() + 1e-12);
  EXPECT_LT(pt.c[0].stderr_mean(), 0.02 * 4.0);
  for (const char* type : {"single", "octave", "mfs"})
    EXPECT_NEAR(test::estimate_li(*make(ctx, type), o, d, 4).c[0].mean, 4.0, 2e-3 * 4.0) << type;
}

// The procedural fire of data/volumes/ draws density, temperature (another voxel size) and a vec3
// colour grid from one OpenVDB file: the tint is the colour grid (in [0, 1]), the core emits, and the
// medium's bounds hold every grid.
TEST(Emission, FireFileDrawsSeveralGrids) {
  const auto file = std::filesystem::path(NIMBUS_SOURCE_DIR) / "data/volumes/fire.vdb";
  if (!std::filesystem::exists(file)) GTEST_SKIP();
  const Scene scene = scene_from_json("{" + test::camera_json() + R"(, "lights": [], "media": [
      {"shape": {"type": "vdb", "file": ")" +
                                      file.string() + R"(", "grid": "density"}, "sigma_s": 10,
       "sigma_a": 2, "temperature_grid": "temperature", "temperature_scale": 1800, "color_grid": "color"}]})");
  const Medium& m = scene.media[0];
  ASSERT_TRUE(m.emission.grids && m.emission.grids->temperature && m.emission.grids->color[2]);
  const SceneMedia media(scene.media);
  EXPECT_TRUE(media.emits());
  const Bounds t = m.emission.grids->temperature->world_bounds();
  EXPECT_TRUE(media.bounds(0).contains(t.lo) && media.bounds(0).contains(t.hi));
  MediumPoint mp;
  double hottest = 0.0;
  for (int k = 0; k < 2000; ++k) {
    const Vec3 p(0.6 * std::sin(k * 1.7), 0.6 * std::cos(k * 2.3), 3.0 * (k + 0.5) / 2000.0);
    media.eval(p, &mp);
    const double d = media.density(0, p);
    hottest = std::max(hottest, mp.emission.x);
    if (d <= 0.0) continue;
    const DensityGrid& r = *m.emission.grids->color[0];
    const double tint = std::clamp(r.density_index(r.world_to_index(p)), 0.0, 1.0);
    EXPECT_NEAR(mp.sigma_s.x, 10.0 * d * tint, 1e-9 * (1.0 + mp.sigma_s.x));
    EXPECT_LE(mp.sigma_s.z, 10.0 * d + 1e-12);
  }
  EXPECT_GT(hottest, 0.0);
}

std::string emission_load_error(const std::string& text) {
  try {
    scene_from_json(text);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(Emission, BadInput) {
  test::ScratchDir dir("emission_bad");
  write_fire(dir / "fire.nvdb", 15.0f);
  const std::string head = "{" + test::camera_json() + R"(, "lights": [], )";
  // A grid named but absent: the scene file, the field and the volume file.
  std::string msg = emission_load_error(head + fire_medium(dir / "fire.nvdb", "", "heat") + "}");
  EXPECT_NE(msg.find("test.json: /media/0/temperature_grid"), std::string::npos) << msg;
  EXPECT_NE(msg.find("fire.nvdb: no grid named \"heat\""), std::string::npos) << msg;
  // Negative temperatures after scale and offset.
  msg = emission_load_error(head + fire_medium(dir / "fire.nvdb", R"(, "temperature_offset": -2000)") + "}");
  EXPECT_NE(msg.find("/media/0/temperature_offset"), std::string::npos) << msg;
  EXPECT_NE(msg.find("must be >= 0"), std::string::npos) << msg;
  msg = emission_load_error(head + fire_medium(dir / "fire.nvdb", R"(, "temperature_scale": -1)") + "}");
  EXPECT_NE(msg.find("/media/0/temperature_scale"), std::string::npos) << msg;
  // Negative emission, grids on a shape without a file, stray fields.
  const std::string sphere = R"("media": [{"shape": {"type": "sphere", "radius": 1}, "sigma_s": 1, )";
  msg = emission_load_error(head + sphere + R"("emission": [1, -1, 0]}]})");
  EXPECT_NE(msg.find("/media/0/emission"), std::string::npos) << msg;
  msg = emission_load_error(head + sphere + R"("emission": 1, "emission_grid": "flame"}]})");
  EXPECT_NE(msg.find("/media/0/emission_grid"), std::string::npos) << msg;
  msg = emission_load_error(head + sphere + R"("intensity": 2}]})");
  EXPECT_NE(msg.find("/media/0/intensity: needs a temperature_grid"), std::string::npos) << msg;
  msg = emission_load_error(head + sphere + R"("emision": 1}]})");
  EXPECT_NE(msg.find("emision"), std::string::npos) << msg;
}

}  // namespace
}  // namespace nimbus
