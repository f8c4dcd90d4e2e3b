// A constant environment image equals the constant environment light in every integrator, within the
// noise (whole-image means over a sphere of medium above a diffuse ground).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include "integrators/registry.h"
#include "nimbus/image.h"
#include "support/scenes.h"
#include "support/scratch_dir.h"
#include "support/stats.h"

namespace nimbus {
namespace {

std::string write_grey_map(const test::ScratchDir& dir) {
  Image img(16, 8);
  for (int j = 0; j < 8; ++j)
    for (int i = 0; i < 16; ++i)
      img.pixel(i, j)[0] = 0.4f, img.pixel(i, j)[1] = 0.5f, img.pixel(i, j)[2] = 0.6f;
  const std::string path = (dir / "grey.exr").string();
  write_exr(path, img);
  return path;
}

// A forward-scattering sphere over a diffuse ground, lit by `env` (a light's JSON), for `integrator`.
Scene sphere_scene(const std::string& env, const std::string& integrator) {
  return test::scene_from_json("{" + test::camera_json() +
                               fmt::format(R"(,
    "media": [{{"shape": {{"type": "sphere", "center": [0, 0, 0], "radius": 1}}, "sigma_s": 2.0,
               "sigma_a": 0.1, "phase": {{"type": "hg", "g": 0.6}}}}],
    "surfaces": [{{"shape": {{"type": "rectangle", "center": [0, 0, -1.2], "normal": [0, 0, 1], "up": [0, 1, 0],
                   "size": [6, 6]}}, "material": {{"type": "diffuse", "albedo": 0.5}}}}],
    "lights": [{}],
    "integrator": {{"type": "{}"{}}}}})",
                                           env, integrator,
                                           integrator == "mfs" ? R"(, "photons": 65536)" : ""));
}

TEST(EnvMapRender, ConstantImageEqualsConstantEnvironment) {
  const test::ScratchDir dir("envmap");
  const std::string file = write_grey_map(dir);
  const std::string constant = R"({"type": "environment", "radiance": [0.4, 0.5, 0.6]})";
  const std::string image = fmt::format(R"({{"type": "environment", "file": "{}"}})", file);
  for (const std::string type : {"pathtrace", "single", "octave", "mfs"}) {
    const Scene a = sphere_scene(constant, type), b = sphere_scene(image, type);
    const SceneContext ca(a), cb(b);
    const auto ia = make_integrator(ca, a.integrator), ib = make_integrator(cb, b.integrator);
    // The whole-image mean over directions through the sphere, onto the ground and out to the sky (mfs's
    // photon grids differ between the two emissions, uniform and by luminance: their noise averages out
    // over the image; 2 % more for it).
    test::MeanAccumulator ma, mb;
    for (int i = 0; i < 20000; ++i) {
      Rng r0(3, i), r1(1, i), r2(2, i);
      const Vec3 d = normalize(Vec3(0.8 * r0.uniform() - 0.4, 1.0, 0.8 * r0.uniform() - 0.4));
      ma.add(average(ia->Li({Vec3(0, -4, 0), d}, r1)));
      mb.add(average(ib->Li({Vec3(0, -4, 0), d}, r2)));
    }
    const double tol =
        5 * std::hypot(ma.stderr_mean(), mb.stderr_mean()) + (type == "mfs" ? 0.02 : 1e-6) * ma.mean;
    EXPECT_NEAR(mb.mean, ma.mean, tol) << type;
    EXPECT_LT(tol, 0.05 * ma.mean) << type;  // power: the check is not vacuous
  }
}

}  // namespace
}  // namespace nimbus
