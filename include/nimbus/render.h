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

// A crop window (render --region): pixels x0 <= x < x1, y0 <= y < y1 of the full image, row 0 at the
// top: half-open, as OpenEXR's data window [x0, x1 - 1] x [y0, y1 - 1]. docs/cli.md.
struct Region {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
};

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
  // Called from worker threads as tiles finish: (pixel samples done, pixel samples to take, the same
  // count of samples), counted over all passes of this render.
  std::function<void(int64_t done, int64_t total, int64_t samples)> progress;
  // Called once before the integrator's set-up (shadow maps, photon grids), with what it makes.
  std::function<void(const std::string& what)> setup;
  // Set to true (e.g. from a signal handler) to stop: the pass under way is dropped and the image is
  // the one of the last whole pass (RenderResult::partial).
  const std::atomic<bool>* cancel = nullptr;
  // > 0: a time budget in seconds, set-up included. The render takes whole passes while they fit (the
  // first pass is always taken) and ends with the spp reached (RenderResult::time_limited).
  double time_limit = 0.0;
  // A film state to continue (render --resume): the samples it holds are kept and the render goes on
  // from its spp to the requested one. Needs the same scene, seed and film; the result equals, bit for
  // bit, the render made in one go. Not with a deep image.
  const FilmState* resume = nullptr;
  // > 0: adaptive sampling (render --noise). Passes go on until the estimated binned relative RMSE
  // against a noise-free image (nimbus compare --bin noise_bin --min-ref 0.05) is at most `noise`,
  // each pixel taking samples as its variance asks; the spp is then the most any pixel may take. Not
  // with a region or a sample range (the passes are planned over the whole image).
  double noise = 0.0;
  int noise_bin = 4;
  // Only these pixels (render --region): the image is the crop, its origin and display size set; each
  // pixel equals the full render's bit for bit (samples are seeded from the pixel in the full image).
  std::optional<Region> region;
  // The first sample index (render --samples START:COUNT): the render takes samples [sample_start,
  // sample_start + spp) of every pixel, the same samples a render of sample_start + spp takes last.
  int sample_start = 0;
};

// The passes of a progressive render: from `done` samples per pixel the next pass goes to twice as many
// (1, 2, 4, ...), the last one to `spp`. A deep image is made in one pass.
int next_pass_spp(int done, int spp);

// Adaptive sampling (RenderOptions::noise) without an spp from the caller (render --noise, Python's
// render(noise=...)): the most samples a pixel may take.
inline constexpr int kAdaptiveDefaultMaxSpp = 4096;

// At most this many deep samples per pixel.
inline constexpr int kMaxDeepSamples = 1024;

struct RenderResult {
  // Premultiplied RGBA (alpha: docs/compositing.md) and the film's layers as EXR channels.
  Image image;
  // The media's contribution along each camera ray (RenderOptions::deep_samples > 0; empty otherwise):
  // flattened, the RGBA of a transparent film.
  DeepImage deep;
  // A transient render (scene film.time_bins; pathtrace only): the steady RGB(A) with the light binned by
  // path length as layers time_under, time0000 .., time_over (render/time_film.h, docs/transient.md),
  // summing to the steady image; empty otherwise.
  Image transient;
  // The exact accumulation state at `spp`, for writing beside the image and resuming (not with deep).
  FilmState state;
  bool partial = false;           // cancelled before the requested spp: the image of the last whole pass
  bool time_limited = false;      // stopped by RenderOptions::time_limit before the requested spp
  int64_t nonfinite_samples = 0;  // NaN/inf (or beyond 4.6e18: render/film.h) samples dropped (this run)
  double seconds = 0.0;
  std::string integrator;
  int spp = 0;            // samples per pixel in the image (adaptive: the most any pixel took)
  double spp_mean = 0.0;  // samples per pixel, the mean over pixels (adaptive sampling, and mfs's outline
                          // pixels, which take edge_samples per pixel sample: scene/edges.h; = spp otherwise)
  double noise_target = 0.0;    // RenderOptions::noise (0: not adaptive)
  double noise_estimate = 0.0;  // adaptive sampling: the estimated binned relative RMSE reached
  int spp_requested = 0;        // what the render asked for
  int sample_start = 0;         // the samples taken: [sample_start, sample_start + spp)
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
