#include "render/film.h"

#include "nimbus/error.h"

namespace nimbus {

Film::Film(int width, int height) : width_(width), height_(height) {
  count_.assign(size_t(width) * size_t(height), 0);
  add_layer("rgb", 3);
}

int Film::add_layer(const std::string& name, int channels) {
  if (layer_index(name) >= 0) throw Error("film layer '" + name + "' exists already");
  if (channels < 1) throw Error("film layer '" + name + "' needs at least one channel");
  layers_.push_back({name, channels, std::vector<double>(size_t(channels) * count_.size(), 0.0)});
  return int(layers_.size()) - 1;
}

int Film::layer_index(const std::string& name) const {
  for (size_t i = 0; i < layers_.size(); ++i)
    if (layers_[i].name == name) return int(i);
  return -1;
}

std::vector<float> Film::resolve_layer(int layer) const {
  const Layer& l = layers_[size_t(layer)];
  std::vector<float> out(l.sum.size(), 0.0f);
  for (size_t i = 0; i < count_.size(); ++i) {
    if (count_[i] == 0) continue;
    for (int c = 0; c < l.channels; ++c) {
      const size_t k = size_t(l.channels) * i + size_t(c);
      out[k] = float(l.sum[k] / count_[i]);
    }
  }
  return out;
}

Image Film::resolve() const {
  Image image(width_, height_);
  image.rgb = resolve_layer(0);  // the same layout: 3 floats per pixel, row 0 at the top
  return image;
}

}  // namespace nimbus
