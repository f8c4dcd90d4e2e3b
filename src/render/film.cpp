#include "render/film.h"

#include <fmt/format.h>

#include <algorithm>

#include "nimbus/error.h"

namespace nimbus {

Film::Film(int width, int height) : width_(width), height_(height) {
  count_.assign(size_t(width) * size_t(height), 0);
  add_layer("rgb", 3);
}

int Film::add_layer(const std::string& name, int channels, int fraction_bits) {
  if (layer_index(name) >= 0) throw Error("film layer '" + name + "' exists already");
  if (channels < 1) throw Error("film layer '" + name + "' needs at least one channel");
  if (fraction_bits < 0 || fraction_bits > 120) throw Error("film layer '" + name + "': bad grid");
  layers_.push_back({name, channels, fraction_bits, std::ldexp(1.0, fraction_bits),
                     std::vector<FilmSum>(size_t(channels) * count_.size(), 0)});
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
      out[k] = float(double(l.sum[k]) / l.scale / count_[i]);
    }
  }
  return out;
}

FilmState Film::state(int spp) const {
  FilmState st;
  st.width = width_;
  st.height = height_;
  st.spp = spp;
  for (const Layer& l : layers_) st.layers.push_back({l.name, l.channels, l.fraction_bits, l.sum});
  st.counts = count_;
  return st;
}

FilmState Film::take_state(int spp) && {
  FilmState st;
  st.width = width_;
  st.height = height_;
  st.spp = spp;
  for (Layer& l : layers_) st.layers.push_back({l.name, l.channels, l.fraction_bits, std::move(l.sum)});
  st.counts = std::move(count_);
  layers_.clear();
  count_.clear();
  return st;
}

void Film::restore(const FilmState& st) {
  if (st.width != width_ || st.height != height_)
    throw Error(fmt::format("resume data: the image is {}x{}, the render {}x{}", st.width, st.height, width_,
                            height_));
  if (st.counts.size() != count_.size()) throw Error("resume data: wrong number of sample counts");
  for (const Layer& l : layers_) {
    const auto it = std::find_if(st.layers.begin(), st.layers.end(),
                                 [&](const FilmState::Layer& s) { return s.name == l.name; });
    if (it == st.layers.end() || it->channels != l.channels || it->sums.size() != l.sum.size())
      throw Error(fmt::format("resume data: no film layer '{}' of {} channels", l.name, l.channels));
    if (it->fraction_bits != l.fraction_bits)
      throw Error(
          fmt::format("resume data: film layer '{}' is summed on a grid of 2^-{}, the render's of 2^-{}",
                      l.name, it->fraction_bits, l.fraction_bits));
  }
  if (st.layers.size() != layers_.size())
    throw Error(
        fmt::format("resume data: {} film layers, the render has {}", st.layers.size(), layers_.size()));
  for (Layer& l : layers_)
    for (const FilmState::Layer& s : st.layers)
      if (s.name == l.name) l.sum = s.sums;
  count_ = st.counts;
}

Image Film::resolve() const {
  Image image(width_, height_);
  image.rgb = resolve_layer(0);  // the same layout: 3 floats per pixel, row 0 at the top
  return image;
}

}  // namespace nimbus
