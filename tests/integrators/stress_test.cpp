// Numerical robustness: extreme scenes render without a single non-finite sample (the film counts
// and drops them, so a NaN anywhere in tracking, phase sampling or NEE shows up here).
#include <gtest/gtest.h>

#include <fmt/format.h>

#include "nimbus/render.h"
#include "support/scenes.h"

namespace nimbus {
namespace {

// A sphere of radius r at the origin seen from 4 r away, with sun, point light and sky.
std::string sphere_scene(double r, double sigma_s, double sigma_a, const std::string& phase, int size, int spp,
                         const std::string& camera_at = "") {
  const std::string cam = camera_at.empty() ? fmt::format("[0, {}, 0]", -4 * r) : camera_at;
  return fmt::format(R"({{"camera": {{"position": {}, "look_at": [0, {}, 0], "up": [0, 0, 1], "fov_y_deg": 40,
      "width": {}, "height": {}}},
    "media": [{{"shape": {{"type": "sphere", "center": [0, 0, 0], "radius": {}}}, "sigma_s": {},
                "sigma_a": {}, "phase": {}}}],
    "lights": [{{"type": "directional", "direction": [0.3, 1, -0.5], "irradiance": 1.0}},
               {{"type": "point", "position": [0, 0, {}], "intensity": 1.0}},
               {{"type": "environment", "radiance": 0.2}}],
    "integrator": {{"type": "pathtrace", "spp": {}}}}})",
                     cam, r, size, size, r, sigma_s, sigma_a, phase, 0.5 * r, spp);
}

void expect_clean(const std::string& json, const std::string& what, const std::string& integrator = "pathtrace") {
  const Scene scene = test::scene_from_json(json);
  RenderOptions opt;
  opt.integrator = integrator;
  const RenderResult r = render(scene, opt);
  EXPECT_EQ(r.nonfinite_samples, 0) << what;
  for (float v : r.image.rgb) {
    ASSERT_TRUE(std::isfinite(v)) << what;
    ASSERT_GE(v, 0.0f) << what;
  }
}

TEST(Stress, ExtremeScenesHaveNoNonFiniteSamples) {
  const std::string hg_fwd = R"({"type": "hg", "g": 0.999})", hg_back = R"({"type": "hg", "g": -0.999})";
  const std::string iso = R"({"type": "isotropic"})";
  for (const std::string& integrator : {"pathtrace", "single"}) {
    expect_clean(sphere_scene(1, 5, 0.1, hg_fwd, 8, 4), "g = 0.999", integrator);
    expect_clean(sphere_scene(1, 5, 0.1, hg_back, 8, 4), "g = -0.999", integrator);
    expect_clean(sphere_scene(1, 3, 0, R"({"type": "double_hg", "g1": 0.999, "g2": -0.999, "w": 0.5})", 8, 4),
                 "double HG, albedo 1", integrator);
    expect_clean(sphere_scene(1, 3, 0, R"({"type": "gauss", "theta2": 1e-6})", 8, 4), "narrow Gaussian", integrator);
    expect_clean(sphere_scene(1e-6, 1e6, 0, iso, 8, 4), "tiny scale", integrator);
    expect_clean(sphere_scene(1e6, 1e-6, 0, iso, 8, 4), "huge scale", integrator);
    // Camera inside the medium, point light inside the medium.
    expect_clean(sphere_scene(1, 2, 0.1, hg_fwd, 8, 4, "[0, -0.2, 0.1]"), "camera inside", integrator);
  }
  // Optical thickness 1000 at albedo 1: about a million scatters per path; a 2x2 image, 1 spp.
  expect_clean(sphere_scene(1, 1000, 0, iso, 2, 1), "optical radius 1000, albedo 1");
}

}  // namespace
}  // namespace nimbus
