// The film: per-pixel sums of samples in named layers and the number of samples each pixel took. The
// driver adds samples; resolve() turns a layer into pixel means. Pixels are independent, so threads that
// render disjoint tiles add without locks; a later pass over the same pixels (a progressive render) adds
// to the same sums.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/math.h"
#include "nimbus/image.h"

namespace nimbus {

class Film {
 public:
  // A film with one RGB layer, "rgb" (index 0: the beauty).
  Film(int width, int height);

  // Adds a layer of `channels` values per pixel; returns its index.
  int add_layer(const std::string& name, int channels);
  int layer_index(const std::string& name) const;  // -1 when absent

  // One camera sample of pixel (x, y): its radiance added to the "rgb" layer when finite (a non-finite
  // sample is dropped and counted: returns false), and the pixel's sample count raised by one.
  bool add_sample(int x, int y, const Rgb& L) {
    const size_t i = index(x, y);
    ++count_[i];
    if (!is_finite(L)) return false;
    double* s = &layers_[0].sum[3 * i];
    s[0] += L[0];
    s[1] += L[1];
    s[2] += L[2];
    return true;
  }
  // Values for another layer at (x, y) (`channels` of them), for the pixel's current sample.
  void add(int layer, int x, int y, const double* values) {
    Layer& l = layers_[size_t(layer)];
    double* s = &l.sum[size_t(l.channels) * index(x, y)];
    for (int c = 0; c < l.channels; ++c) s[c] += values[c];
  }

  int width() const { return width_; }
  int height() const { return height_; }
  uint32_t samples(int x, int y) const { return count_[index(x, y)]; }
  // A layer's sums at (x, y): `channels` doubles.
  const double* sums(int layer, int x, int y) const {
    const Layer& l = layers_[size_t(layer)];
    return &l.sum[size_t(l.channels) * index(x, y)];
  }
  // The "rgb" layer's pixel means (sum / samples; 0 where a pixel has no samples).
  Image resolve() const;
  // Any layer's pixel means, `channels` floats per pixel, row 0 at the top.
  std::vector<float> resolve_layer(int layer) const;

  // The exact state (every layer's sums, the sample counts), to stop a render and resume it bit for bit.
  FilmState state(int spp) const;
  // Restores a state taken from a film with the same size and layers; throws nimbus::Error otherwise.
  void restore(const FilmState& state);

 private:
  struct Layer {
    std::string name;
    int channels = 0;
    std::vector<double> sum;
  };
  size_t index(int x, int y) const { return size_t(y) * size_t(width_) + size_t(x); }

  int width_ = 0, height_ = 0;
  std::vector<Layer> layers_;
  std::vector<uint32_t> count_;
};

}  // namespace nimbus
