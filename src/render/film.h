// The film: per-pixel sums of samples in named layers and the number of samples each pixel took. The
// driver adds samples; resolve() turns a layer into pixel means. Pixels are independent, so threads that
// render disjoint tiles add without locks; a later pass over the same pixels (a progressive render) adds
// to the same sums.
//
// The sums are fixed point (nimbus/image.h: FilmSum): each sample's value is rounded once, to the nearest
// multiple of the layer's grid 2^-fraction_bits (ties to even), and added as a 128-bit integer. Integer
// addition is associative, so sums of disjoint sample ranges added afterwards (nimbus merge, render
// --samples) equal the sum made sample by sample bit for bit. The grid of 2^-64 is far finer than the
// float rounding of the pixel values a film sees (pixel means of 1e-10 and up come out as double sums
// gave them, to a float ulp); a sample below half a step (2.7e-20) adds 0.
// A value beyond +-2^(kFilmSampleBits - fraction_bits) (4.6e18 on the 2^-64 grid) does not fit: the beauty
// drops such a sample as it drops a non-finite one, other layers take it saturated to that bound. A sum
// that would leave +-(2^127 - 1) (9.2e18 on the 2^-64 grid) saturates there: that pixel is then wrong,
// and no longer exact under merges, but never undefined.
#pragma once

#include <bit>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "core/math.h"
#include "nimbus/image.h"

namespace nimbus {

// The grid of every layer but adaptive sampling's squared luminances (render/adaptive.h): 2^-64.
inline constexpr int kFilmFractionBits = 64;

// x rounded to the nearest integer, ties to even, exactly (no double rounding); |x| <= 2^kFilmSampleBits.
inline FilmSum film_round(double x) {
  const uint64_t bits = std::bit_cast<uint64_t>(x);
  const int e = int((bits >> 52) & 0x7ff);  // x = m 2^(e - 1075), m = 53 bits with the leading one
  if (e < 1022) return 0;                   // |x| < 1/2
  const uint64_t m = (bits & ((uint64_t(1) << 52) - 1)) | (uint64_t(1) << 52);
  FilmSum q;
  if (e >= 1075) {
    q = FilmSum(m) << (e - 1075);
  } else {
    const int r = 1075 - e;  // 1 .. 53 fraction bits to round away
    const uint64_t rest = m & ((uint64_t(1) << r) - 1), half = uint64_t(1) << (r - 1);
    uint64_t whole = m >> r;
    whole += rest > half || (rest == half && (whole & 1));
    q = FilmSum(whole);
  }
  return bits >> 63 ? -q : q;
}

// a + b, saturated at +-(2^127 - 1) (never UB).
inline FilmSum film_add(FilmSum a, FilmSum b) {
  __extension__ typedef unsigned __int128 Bits;
  FilmSum s;
  if (!__builtin_add_overflow(a, b, &s)) return s;
  const FilmSum max = FilmSum(~Bits(0) >> 1);
  return b > 0 ? max : -max;
}

class Film {
 public:
  // A film with one RGB layer, "rgb" (index 0: the beauty).
  Film(int width, int height);

  // Adds a layer of `channels` values per pixel, summed on a grid of 2^-fraction_bits; returns its index.
  int add_layer(const std::string& name, int channels, int fraction_bits = kFilmFractionBits);
  int layer_index(const std::string& name) const;  // -1 when absent

  // One camera sample of pixel (x, y): its radiance added to the "rgb" layer when finite and within the
  // grid's range (otherwise the sample is dropped and counted: returns false), and the pixel's sample
  // count raised by one.
  bool add_sample(int x, int y, const Rgb& L) {
    const size_t i = index(x, y);
    ++count_[i];
    const Layer& l = layers_[0];
    const double v[3] = {L[0] * l.scale, L[1] * l.scale, L[2] * l.scale};
    if (!(std::abs(v[0]) <= kLimit && std::abs(v[1]) <= kLimit && std::abs(v[2]) <= kLimit)) return false;
    FilmSum* s = &layers_[0].sum[3 * i];
    for (int c = 0; c < 3; ++c) s[c] = film_add(s[c], film_round(v[c]));
    return true;
  }
  // Values for another layer at (x, y) (`channels` of them), for the pixel's current sample. A value
  // beyond the layer's range is saturated to it; a NaN adds 0.
  void add(int layer, int x, int y, const double* values) {
    Layer& l = layers_[size_t(layer)];
    FilmSum* s = &l.sum[size_t(l.channels) * index(x, y)];
    for (int c = 0; c < l.channels; ++c) {
      double v = values[c] * l.scale;
      if (!(std::abs(v) <= kLimit)) v = std::isnan(v) ? 0.0 : std::copysign(kLimit, v);
      s[c] = film_add(s[c], film_round(v));
    }
  }

  int width() const { return width_; }
  int height() const { return height_; }
  uint32_t samples(int x, int y) const { return count_[index(x, y)]; }
  // Channel c of a layer's sum at (x, y), as the double nearest to it.
  double sum(int layer, int x, int y, int c) const {
    const Layer& l = layers_[size_t(layer)];
    return double(l.sum[size_t(l.channels) * index(x, y) + size_t(c)]) / l.scale;
  }
  // The "rgb" layer's pixel means (sum / samples; 0 where a pixel has no samples).
  Image resolve() const;
  // Any layer's pixel means, `channels` floats per pixel, row 0 at the top.
  std::vector<float> resolve_layer(int layer) const;

  // The exact state (every layer's sums, the sample counts), to stop a render and resume it bit for bit.
  FilmState state(int spp) const;
  // The same, its sums moved out rather than copied (the film is left with no layers or counts): for the
  // end of a render, where the film is read no more.
  FilmState take_state(int spp) &&;
  // Restores a state taken from a film with the same size and layers; throws nimbus::Error otherwise.
  void restore(const FilmState& state);

 private:
  static constexpr double kLimit = 0x1p126;  // 2^kFilmSampleBits grid steps
  static_assert(kFilmSampleBits == 126);
  struct Layer {
    std::string name;
    int channels = 0;
    int fraction_bits = 0;
    double scale = 1.0;  // 2^fraction_bits
    std::vector<FilmSum> sum;
  };
  size_t index(int x, int y) const { return size_t(y) * size_t(width_) + size_t(x); }

  int width_ = 0, height_ = 0;
  std::vector<Layer> layers_;
  std::vector<uint32_t> count_;
};

}  // namespace nimbus
