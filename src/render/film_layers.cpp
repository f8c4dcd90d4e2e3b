#include "render/film_layers.h"

#include <fmt/format.h>

#include <algorithm>
#include <limits>

#include "nimbus/error.h"

namespace nimbus {

namespace {

bool wants(const FilmSettings& settings, const std::string& name) {
  return std::find(settings.layers.begin(), settings.layers.end(), name) != settings.layers.end();
}

// A film layer's pixel means as EXR channels: `names` one per channel of the layer.
void add_channels(Image& image, const std::vector<float>& means, const std::vector<std::string>& names) {
  const size_t n = size_t(image.width) * size_t(image.height), k = names.size();
  for (size_t c = 0; c < k; ++c) {
    ImageChannel ch{names[c], std::vector<float>(n)};
    for (size_t i = 0; i < n; ++i) ch.data[i] = means[k * i + c];
    image.channels.push_back(std::move(ch));
  }
}

void add_rgb(Film& film, int layer, int x, int y, const Rgb& v) {
  if (layer < 0 || !is_finite(v)) return;
  const double values[3] = {v[0], v[1], v[2]};
  film.add(layer, x, y, values);
}

}  // namespace

double sample_alpha(const CameraSample& s, bool background_opaque) {
  return 1.0 - average(s.holdout_transmittance) - (background_opaque ? 0.0 : average(s.escape_transmittance));
}

void check_film_layers(const std::vector<std::string>& layers) {
  const std::vector<std::string>& known = film_layer_names();
  for (auto it = layers.begin(); it != layers.end(); ++it) {
    if (std::find(known.begin(), known.end(), *it) == known.end())
      throw Error(fmt::format("unknown film layer '{}' (known: {})", *it, fmt::join(known, ", ")));
    if (std::find(layers.begin(), it, *it) != it)
      throw Error(fmt::format("film layer '{}' named twice", *it));
  }
}

FilmLayers::FilmLayers(Film& film, const FilmSettings& settings, bool has_environment)
    : transparent_(settings.transparent), background_opaque_(has_environment && !settings.transparent) {
  check_film_layers(settings.layers);
  alpha_ = film.add_layer("alpha", 1);
  if (wants(settings, "depth")) depth_ = film.add_layer("depth", 2);  // sum of finite depths, their count
  if (wants(settings, "transmittance")) transmittance_ = film.add_layer("transmittance", 3);
  indirect_ = wants(settings, "indirect");
  direct_wanted_ = wants(settings, "direct");
  if (indirect_ || direct_wanted_) direct_ = film.add_layer("direct", 3);
  if (wants(settings, "albedo")) albedo_ = film.add_layer("albedo", 3);
  if (wants(settings, "normal")) normal_ = film.add_layer("normal", 3);
  samples_ = wants(settings, "samples");
}

bool FilmLayers::add(Film& film, int x, int y, const Rgb& L, const CameraSample& s) const {
  // The beauty: on an opaque film exactly Li (the images of a film without layers are unchanged).
  if (!film.add_sample(x, y, beauty(L, s))) return false;
  const double alpha = sample_alpha(s, background_opaque_);
  if (std::isfinite(alpha)) film.add(alpha_, x, y, &alpha);
  if (depth_ >= 0 && std::isfinite(s.depth)) {
    const double values[2] = {s.depth, 1.0};
    film.add(depth_, x, y, values);
  }
  add_rgb(film, transmittance_, x, y, s.escape_transmittance);
  // direct + indirect = the beauty: a transparent film takes the background out of direct too.
  add_rgb(film, direct_, x, y, transparent_ ? s.direct - s.background : s.direct);
  add_rgb(film, albedo_, x, y, s.albedo);
  add_rgb(film, normal_, x, y, s.normal);
  return true;
}

Image FilmLayers::resolve(const Film& film) const {
  Image image = film.resolve();
  image.alpha = film.resolve_layer(alpha_);
  const size_t n = size_t(image.width) * size_t(image.height);
  if (depth_ >= 0) {
    // The mean over the samples with a finite depth (sums over a common count); infinity where none.
    const std::vector<float> sums = film.resolve_layer(depth_);
    ImageChannel z{"Z", std::vector<float>(n)};
    for (size_t i = 0; i < n; ++i)
      z.data[i] =
          sums[2 * i + 1] > 0.0f ? sums[2 * i] / sums[2 * i + 1] : std::numeric_limits<float>::infinity();
    image.channels.push_back(std::move(z));
  }
  if (transmittance_ >= 0)
    add_channels(image, film.resolve_layer(transmittance_),
                 {"transmittance.R", "transmittance.G", "transmittance.B"});
  if (direct_ >= 0) {
    const std::vector<float> direct = film.resolve_layer(direct_);
    if (direct_wanted_) add_channels(image, direct, {"direct.R", "direct.G", "direct.B"});
    if (indirect_) {  // the beauty less direct, from the same pixel means
      std::vector<float> indirect(direct.size());
      for (size_t i = 0; i < direct.size(); ++i) indirect[i] = image.rgb[i] - direct[i];
      add_channels(image, indirect, {"indirect.R", "indirect.G", "indirect.B"});
    }
  }
  if (albedo_ >= 0) add_channels(image, film.resolve_layer(albedo_), {"albedo.R", "albedo.G", "albedo.B"});
  if (normal_ >= 0) add_channels(image, film.resolve_layer(normal_), {"normal.X", "normal.Y", "normal.Z"});
  if (samples_) {
    ImageChannel count{"samples.X", std::vector<float>(n)};
    for (int y = 0; y < image.height; ++y)
      for (int x = 0; x < image.width; ++x)
        count.data[size_t(y) * image.width + x] = float(film.samples(x, y));
    image.channels.push_back(std::move(count));
  }
  return image;
}

}  // namespace nimbus
