// The random number generator's stream bookkeeping: Rng::draws_since counts the numbers drawn.
#include "core/rng.h"

#include <gtest/gtest.h>

namespace nimbus {
namespace {

TEST(Rng, DrawsSinceCountsTheNumbersDrawn) {
  for (uint64_t k : {0ull, 1ull, 2ull, 7ull, 1000ull, 123457ull}) {
    Rng rng = Rng::for_sample(42, 3, 5, k);
    const uint64_t start = rng.state();
    for (uint64_t i = 0; i < k; ++i) rng.next_u32();
    EXPECT_EQ(rng.draws_since(start), k);
    rng.uniform();  // two numbers
    EXPECT_EQ(rng.draws_since(start), k + 2);
  }
}

}  // namespace
}  // namespace nimbus
