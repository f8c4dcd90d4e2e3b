// Bit-for-bit comparison of images and buffers.
#pragma once

#include <cstring>
#include <vector>

namespace nimbus::test {

inline bool same_floats(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

}  // namespace nimbus::test
