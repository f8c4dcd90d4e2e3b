// ZeroedFloats (core/zeroed_floats.h): zero at the start (small arrays from calloc, large ones from fresh
// huge-page-advised mappings), writable everywhere, and moved without copying or double freeing.
#include "core/zeroed_floats.h"

#include <gtest/gtest.h>

namespace nimbus {
namespace {

TEST(ZeroedFloats, ZeroAtStartAndWritable) {
  for (size_t n : {size_t(0), size_t(1), size_t(1000), size_t(3) << 20}) {  // 12 MiB: the mapped path
    ZeroedFloats a(n);
    ASSERT_EQ(a.size(), n);
    size_t nonzero = 0;
    for (size_t i = 0; i < n; ++i) nonzero += a[i] != 0.0f;
    EXPECT_EQ(nonzero, 0u) << n;
    for (size_t i = 0; i < n; i += 4097) a[i] = float(i);
    if (n > 0) a[n - 1] = 7.0f;
    for (size_t i = 0; i + 1 < n; i += 4097) EXPECT_EQ(a[i], float(i));
    if (n > 0) EXPECT_EQ(a[n - 1], 7.0f);
  }
}

TEST(ZeroedFloats, MoveHandsOverTheArray) {
  ZeroedFloats a(size_t(1) << 20);
  a[5] = 3.0f;
  const float* p = a.data();
  ZeroedFloats b(std::move(a));
  EXPECT_EQ(b.data(), p);
  EXPECT_EQ(b[5], 3.0f);
  ZeroedFloats c(10);
  c = std::move(b);
  EXPECT_EQ(c.data(), p);
  EXPECT_EQ(c.size(), size_t(1) << 20);
}

// FloatArray: a std::vector whose large blocks are huge-page mappings (2 MiB-aligned on Linux); filled,
// grown past the mapping threshold (a copy into a new block), copied and freed like any vector (ASan
// checks the frees).
TEST(FloatArray, BehavesAsAVector) {
  FloatArray a(1000, 2.0f);  // the heap
  EXPECT_EQ(a[999], 2.0f);
  a.resize(size_t(1) << 20, 1.0f);  // 4 MiB: mapped
#if defined(__linux__)
  EXPECT_EQ(reinterpret_cast<size_t>(a.data()) % (size_t(2) << 20), 0u);
#endif
  EXPECT_EQ(a[999], 2.0f);
  EXPECT_EQ(a[1000], 1.0f);
  EXPECT_EQ(a.back(), 1.0f);
  FloatArray b = a;
  b[7] = 5.0f;
  EXPECT_EQ(a[7], 2.0f);
  EXPECT_EQ(b[7], 5.0f);
  const FloatArray zero(size_t(3) << 20);  // value-initialised: zero
  size_t nonzero = 0;
  for (float v : zero) nonzero += v != 0.0f;
  EXPECT_EQ(nonzero, 0u);
  a.clear();
  a.shrink_to_fit();
  EXPECT_TRUE(a.empty());
}

}  // namespace
}  // namespace nimbus
