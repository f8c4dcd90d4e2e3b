// Shared by the stress tests: an extreme sphere scene and the check that a render is clean.
#pragma once

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "nimbus/render.h"
#include "support/scenes.h"

namespace nimbus::test {

// A sphere of radius r at the origin seen from 4 r away, with sun, point light and sky.
inline std::string stress_sphere(double r, double sigma_s, double sigma_a, const std::string& phase, int size,
                                 int spp, const std::string& camera_at = "") {
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

// Renders with `integrator`: no non-finite sample, every pixel finite and non-negative.
inline void expect_clean(const std::string& json, const std::string& what,
                         const std::string& integrator = "pathtrace") {
  const Scene scene = scene_from_json(json);
  RenderOptions opt;
  opt.integrator = integrator;
  const RenderResult r = render(scene, opt);
  EXPECT_EQ(r.nonfinite_samples, 0) << what;
  for (float v : r.image.rgb) {
    ASSERT_TRUE(std::isfinite(v)) << what;
    ASSERT_GE(v, 0.0f) << what;
  }
}

}  // namespace nimbus::test
