// (Slow) numerical robustness: mfs in the optically thickest case. Its photon grid must stay within its
// work budget (bounded time: ~30 s here, hours without it) and produce finite light.
#include <gtest/gtest.h>

#include "support/stress.h"

namespace nimbus {
namespace {

using test::expect_clean;
using test::stress_sphere;

TEST(StressSlow, MfsOpticallyThickMediumIsBoundedAndFinite) {
  expect_clean(stress_sphere(1, 1000, 0, R"({"type": "hg", "g": 0.85})", 4, 1), "optical radius 1000, mfs",
               "mfs");
}

}  // namespace
}  // namespace nimbus
