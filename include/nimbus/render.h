// Rendering a scene: options, progress and cancellation callbacks, the result.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>

#include "nimbus/image.h"
#include "nimbus/scene.h"

namespace nimbus {

struct RenderOptions {
  std::optional<int> spp;        // overrides the scene's integrator.spp
  std::optional<uint64_t> seed;  // overrides integrator.seed
  // Overrides integrator.type; another integrator than the scene's starts from its own defaults (the
  // scene's integrator fields belong to the integrator it names).
  std::optional<std::string> integrator;
  // Overrides the scene's film.layers (names from film_layer_names(); an unknown name is an error).
  std::optional<std::vector<std::string>> layers;
  // > 0: also make a deep image of at most this many samples per pixel (RenderResult::deep).
  int deep_samples = 0;
  int threads = 0;  // 0 = all hardware threads
  int tile_size = 16;
  // Called from worker threads as tiles finish: (tiles done, tiles total, samples so far).
  std::function<void(int64_t done, int64_t total, int64_t samples)> progress;
  // Set to true (e.g. from a signal handler) to stop at the next tile.
  const std::atomic<bool>* cancel = nullptr;
};

// At most this many deep samples per pixel.
inline constexpr int kMaxDeepSamples = 1024;

struct RenderResult {
  // Premultiplied RGBA (alpha: docs/compositing.md) and the film's layers as EXR channels.
  Image image;
  // The media's contribution along each camera ray (RenderOptions::deep_samples > 0; empty otherwise):
  // flattened, the RGBA of a transparent film.
  DeepImage deep;
  bool partial = false;  // cancelled: tiles not rendered are black
  int64_t tiles_done = 0, tiles_total = 0;
  int64_t nonfinite_samples = 0;  // NaN/inf samples found and dropped by the film
  double seconds = 0.0;
  std::string integrator;
  int spp = 0;
  uint64_t seed = 0;
  // The integrator block as rendered: type, spp, seed, max_events and the integrator's own fields with
  // "auto" choices resolved (also in the EXR header as nimbus/integrator_settings).
  nlohmann::json settings;
  ImageMetadata metadata;  // scene and settings, for the EXR header
};

// Names of the available integrators.
std::vector<std::string> integrator_names();

RenderResult render(const Scene& scene, const RenderOptions& options = {});

}  // namespace nimbus
