// Numerical robustness: extreme scenes render without a single non-finite sample (the film counts
// and drops them, so a NaN anywhere in tracking, phase sampling or NEE shows up here).
#include "support/stress.h"

#include <gtest/gtest.h>

namespace nimbus {
namespace {

using test::expect_clean;
using test::stress_sphere;

TEST(Stress, ExtremeScenesHaveNoNonFiniteSamples) {
  const std::string hg_fwd = R"({"type": "hg", "g": 0.999})", hg_back = R"({"type": "hg", "g": -0.999})";
  const std::string iso = R"({"type": "isotropic"})";
  for (const std::string& integrator : {"pathtrace", "single", "mfs", "octave"}) {
    expect_clean(stress_sphere(1, 5, 0.1, hg_fwd, 8, 4), "g = 0.999", integrator);
    expect_clean(stress_sphere(1, 5, 0.1, hg_back, 8, 4), "g = -0.999", integrator);
    expect_clean(
        stress_sphere(1, 3, 0, R"({"type": "double_hg", "g1": 0.999, "g2": -0.999, "w": 0.5})", 8, 4),
        "double HG, albedo 1", integrator);
    expect_clean(stress_sphere(1, 3, 0, R"({"type": "gauss", "theta2": 1e-6})", 8, 4), "narrow Gaussian",
                 integrator);
    expect_clean(stress_sphere(1e-6, 1e6, 0, iso, 8, 4), "tiny scale", integrator);
    expect_clean(stress_sphere(1e6, 1e-6, 0, iso, 8, 4), "huge scale", integrator);
    // Camera inside the medium, point light inside the medium.
    expect_clean(stress_sphere(1, 2, 0.1, hg_fwd, 8, 4, "[0, -0.2, 0.1]"), "camera inside", integrator);
  }
  // Optical thickness 1000 at albedo 1: about a million scatters per path; a 2x2 image, 1 spp.
  expect_clean(stress_sphere(1, 1000, 0, iso, 2, 1), "optical radius 1000, albedo 1");
}

}  // namespace
}  // namespace nimbus
