// The film's compositing layers: what a camera sample (integrators/integrator.h: CameraSample) adds to
// the film, and how the pixel means become the image's alpha and EXR channels. docs/compositing.md
// defines each; the EXR channel names follow the conventions Nuke, Blender and OpenImageIO read:
//     RGBA in the default layer (premultiplied), depth as Z, the others as layer.channel:
//     transmittance.R/G/B, direct.R/G/B, indirect.R/G/B, albedo.R/G/B, normal.X/Y/Z, samples.X.
#pragma once

#include <string>
#include <vector>

#include "integrators/integrator.h"
#include "nimbus/image.h"
#include "nimbus/scene.h"
#include "render/film.h"

namespace nimbus {

// alpha = 1 - mean(escape_transmittance) - mean(holdout_transmittance) on a transparent film or where
// the scene has no environment light; 1 - mean(holdout_transmittance) where the environment is an opaque
// background (the channel mean, as compositors take one alpha for three colours).
double sample_alpha(const CameraSample& s, bool background_opaque);

// Throws nimbus::Error for a layer name not in film_layer_names() or named twice.
void check_film_layers(const std::vector<std::string>& layers);

class FilmLayers {
 public:
  // Adds the layers `settings` asks for (and alpha, always) to `film` (check_film_layers first).
  FilmLayers(Film& film, const FilmSettings& settings, bool has_environment);

  // Whether any layer needs the sample's depth or albedo.
  bool depth_wanted() const { return depth_ >= 0 || albedo_ >= 0; }
  // What the beauty takes of a sample: L, less the background on a transparent film.
  Rgb beauty(const Rgb& L, const CameraSample& s) const { return transparent_ ? L - s.background : L; }
  // One camera sample of pixel (x, y): its radiance L (less the background on a transparent film) and
  // layers. A non-finite L is dropped from every layer (counted as a sample): returns false.
  bool add(Film& film, int x, int y, const Rgb& L, const CameraSample& s) const;
  // The premultiplied RGBA and the layers' channels, pixel means.
  Image resolve(const Film& film) const;

 private:
  bool transparent_ = false, background_opaque_ = false, indirect_ = false, direct_wanted_ = false,
       samples_ = false;
  int alpha_ = -1, depth_ = -1, transmittance_ = -1, direct_ = -1, albedo_ = -1, normal_ = -1;
};

}  // namespace nimbus
