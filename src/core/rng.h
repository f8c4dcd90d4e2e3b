// Random numbers: PCG32 (O'Neill 2014) seeded by hashing (seed, pixel, sample index), so every
// sample's stream is fixed by its coordinates and images do not depend on the thread count.
#pragma once

#include <cstdint>

namespace nimbus {

// SplitMix64 finaliser: a good 64-bit mixer for building seeds from coordinates.
inline uint64_t mix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

class Rng {
 public:
  Rng() : Rng(0, 0) {}
  Rng(uint64_t seed, uint64_t stream) {
    inc_ = (mix64(stream) << 1u) | 1u;
    state_ = 0;
    next_u32();
    state_ += mix64(seed);
    next_u32();
  }
  // The stream of sample `index` of pixel (x, y) for a render seeded with `seed`.
  static Rng for_sample(uint64_t seed, uint32_t x, uint32_t y, uint64_t index) {
    return Rng(mix64(seed ^ mix64((uint64_t(x) << 32) | y)), index);
  }

  uint32_t next_u32() {
    const uint64_t old = state_;
    state_ = old * 6364136223846793005ull + inc_;
    const uint32_t xorshifted = uint32_t(((old >> 18u) ^ old) >> 27u);
    const uint32_t rot = uint32_t(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((~rot + 1u) & 31));
  }
  // How many numbers (next_u32 calls) this stream has drawn since it was at state `from`: the PCG
  // state's distance along its sequence, found bit by bit from the lowest (the low k bits of an LCG
  // repeat with period 2^k). Adaptive sampling takes it as a sample's cost, the same on any machine.
  uint64_t draws_since(uint64_t from) const {
    uint64_t cur = from, mult = 6364136223846793005ull, inc = inc_, bit = 1, steps = 0;
    while (cur != state_ && bit != 0) {
      if ((cur & bit) != (state_ & bit)) {
        cur = cur * mult + inc;
        steps |= bit;
      }
      bit <<= 1;
      inc = (mult + 1) * inc;
      mult *= mult;
    }
    return steps;
  }
  uint64_t state() const { return state_; }

  // Uniform in [0, 1), 53 random bits.
  double uniform() {
    const uint64_t hi = next_u32(), lo = next_u32();
    return double(((hi << 32) | lo) >> 11) * 0x1.0p-53;
  }

 private:
  uint64_t state_ = 0, inc_ = 1;
};

}  // namespace nimbus
