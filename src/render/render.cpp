// The driver: resolves the render's settings, builds the scene context and the integrator through the
// registry, makes the camera rays and adds their radiance to the film, tile by tile over oneTBB. Every
// sample is seeded from (seed, pixel, sample index), so the image is bit-identical for any thread
// count; progress and cancellation go through callbacks.
#include "nimbus/render.h"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <chrono>
#include <cmath>
#include <memory>
#include <optional>

#include "integrators/registry.h"
#include "nimbus/error.h"
#include "render/deep.h"
#include "render/film.h"
#include "render/film_layers.h"

namespace nimbus {

namespace {

// The R2 sequence's steps: 1 / p and 1 / p^2 for the plastic number p = 1.3247179572...
constexpr double kR2a1 = 0.75487766624669276, kR2a2 = 0.56984029099805327;

// The scene's integrator block with the render's overrides. A different integrator named by the options
// starts from its own defaults: the scene's fields belong to the integrator the scene names.
IntegratorSettings resolve_settings(const Scene& scene, const RenderOptions& options) {
  IntegratorSettings settings = scene.integrator;
  if (options.spp) settings.spp = *options.spp;
  if (options.seed) settings.seed = *options.seed;
  if (options.integrator && *options.integrator != settings.type) {
    find_integrator(*options.integrator);  // an unknown name is an error naming the known ones
    settings.type = *options.integrator;
    settings.options = nlohmann::json::object();
  }
  if (settings.spp < 1 || settings.spp > kMaxSpp)
    throw Error(fmt::format("spp must be between 1 and {}", kMaxSpp));
  if (options.threads < 0) throw Error("threads must be >= 0");
  if (options.tile_size < 1) throw Error("tile size must be >= 1");
  if (options.layers) check_film_layers(*options.layers);  // before any precomputation
  if (options.deep_samples < 0 || options.deep_samples > kMaxDeepSamples)
    throw Error(fmt::format("deep samples must be between 1 and {} (0: no deep image)", kMaxDeepSamples));
  return settings;
}

// The integrator block as rendered: common fields and the integrator's resolved settings.
nlohmann::json resolved_block(const IntegratorSettings& settings, const Integrator& integrator) {
  nlohmann::json block = {{"type", settings.type},
                          {"spp", settings.spp},
                          {"seed", settings.seed},
                          {"max_events", settings.max_events}};
  const nlohmann::json own = integrator.settings_json();
  for (const auto& [key, value] : own.items()) block[key] = value;
  return block;
}

// What the film needs of every camera sample: its layers and, for a deep image, the pixel's segments
// (reused from pixel to pixel by one thread) and where its deep samples go.
struct PixelTargets {
  Film& film;
  const FilmLayers& layers;
  int deep_samples = 0;                               // 0: no deep image
  std::vector<std::vector<DeepSample>>* deep_pixels;  // per pixel, when deep_samples > 0
};

// Samples of pixel (x, y) into the film. Positions in the pixel: the R2 sequence (Roberts 2018), shifted
// by a random offset per pixel (a Cranley-Patterson rotation, so each sample is still uniform over the
// pixel and the estimate unbiased); its samples are spread evenly for every spp, which halves edge noise
// at a few spp. Returns the number of non-finite samples (dropped).
int64_t render_pixel(const Integrator& integrator, const PinholeCamera& camera,
                     const IntegratorSettings& settings, int x, int y, const PixelTargets& to) {
  Rng shift = Rng::for_sample(settings.seed, uint32_t(x), uint32_t(y), ~uint64_t(0));
  const double ux = shift.uniform(), uy = shift.uniform();
  int64_t bad = 0;
  thread_local std::vector<DeepSegment> segments, sample_segments;
  segments.clear();
  for (int s = 0; s < settings.spp; ++s) {
    Rng rng = Rng::for_sample(settings.seed, uint32_t(x), uint32_t(y), uint64_t(s));
    double jx = ux + s * kR2a1, jy = uy + s * kR2a2;
    jx -= std::floor(jx);
    jy -= std::floor(jy);
    CameraSample sample;
    sample.depth_wanted = to.layers.depth_wanted();
    sample_segments.clear();
    if (to.deep_samples > 0) sample.deep = &sample_segments;
    const Rgb L = integrator.Li(camera.generate_ray(x + jx, y + jy), rng, &sample);
    if (!to.layers.add(to.film, x, y, L, sample)) {
      ++bad;
      continue;  // a dropped sample adds nothing to the deep pixel either
    }
    segments.insert(segments.end(), sample_segments.begin(), sample_segments.end());
  }
  if (to.deep_samples > 0) {
    const size_t i = size_t(y) * size_t(to.film.width()) + size_t(x);
    merge_deep_segments(segments, 1.0 / settings.spp, to.deep_samples, &(*to.deep_pixels)[i]);
  }
  return bad;
}

// The pixels' deep samples as one deep image.
DeepImage assemble_deep(int width, int height, std::vector<std::vector<DeepSample>>& pixels) {
  DeepImage deep;
  deep.width = width;
  deep.height = height;
  deep.offsets.assign(pixels.size() + 1, 0);
  for (size_t i = 0; i < pixels.size(); ++i) deep.offsets[i + 1] = deep.offsets[i] + pixels[i].size();
  deep.samples.reserve(deep.offsets.back());
  for (auto& p : pixels) {
    deep.samples.insert(deep.samples.end(), p.begin(), p.end());
    std::vector<DeepSample>().swap(p);
  }
  return deep;
}

}  // namespace

RenderResult render(const Scene& scene, const RenderOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const IntegratorSettings settings = resolve_settings(scene, options);

  // Every parallel part, the integrator's precomputation (shadow maps, photon grids) included, runs in
  // an arena of the requested size.
  const int threads = options.threads > 0 ? options.threads : tbb::this_task_arena::max_concurrency();
  tbb::task_arena arena(threads);
  std::optional<SceneContext> context;
  std::unique_ptr<Integrator> integrator;
  arena.execute([&] {
    context.emplace(scene);
    integrator = make_integrator(*context, settings, scene.file.empty() ? "scene" : scene.file.string());
  });

  RenderResult result;
  result.integrator = settings.type;
  result.spp = settings.spp;
  result.seed = settings.seed;
  const int W = scene.camera.width, H = scene.camera.height, ts = options.tile_size;
  Film film(W, H);
  FilmSettings film_settings = scene.film;
  if (options.layers) film_settings.layers = *options.layers;
  const FilmLayers layers(film, film_settings, context->has_environment);
  std::vector<std::vector<DeepSample>> deep_pixels(options.deep_samples > 0 ? size_t(W) * size_t(H) : 0);
  const PixelTargets targets{film, layers, options.deep_samples, &deep_pixels};
  const int tiles_x = (W + ts - 1) / ts, tiles_y = (H + ts - 1) / ts;
  result.tiles_total = int64_t(tiles_x) * tiles_y;

  std::atomic<int64_t> tiles_done{0}, nonfinite{0}, samples{0};
  std::atomic<bool> stopped{false};
  auto cancelled = [&] { return options.cancel && options.cancel->load(std::memory_order_relaxed); };
  auto render_tile = [&](int64_t tile) {
    const int x0 = int(tile % tiles_x) * ts, y0 = int(tile / tiles_x) * ts;
    const int x1 = std::min(x0 + ts, W), y1 = std::min(y0 + ts, H);
    int64_t bad = 0;
    for (int y = y0; y < y1; ++y) {
      // Stay responsive inside long tiles: abandon the tile (it counts as not done).
      if (cancelled()) {
        stopped = true;
        nonfinite += bad;
        return;
      }
      for (int x = x0; x < x1; ++x)
        bad += render_pixel(*integrator, context->camera, settings, x, y, targets);
    }
    nonfinite += bad;
    const int64_t done = ++tiles_done;
    const int64_t total_samples = samples += int64_t(x1 - x0) * (y1 - y0) * settings.spp;
    if (options.progress) options.progress(done, result.tiles_total, total_samples);
  };

  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<int64_t>(0, result.tiles_total, 1),
                      [&](const tbb::blocked_range<int64_t>& r) {
                        for (int64_t t = r.begin(); t != r.end(); ++t) render_tile(t);
                      });
  });

  result.image = layers.resolve(film);
  if (options.deep_samples > 0) result.deep = assemble_deep(W, H, deep_pixels);
  result.tiles_done = tiles_done;
  result.partial = stopped || tiles_done < result.tiles_total;
  result.nonfinite_samples = nonfinite;
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  // The header says exactly how the image was made: the scene as rendered, with its integrator block
  // replaced by the resolved one (overrides applied, "auto" choices made).
  result.settings = resolved_block(settings, *integrator);
  nlohmann::json rendered = scene.source.is_object() ? scene.source : nlohmann::json::object();
  rendered["integrator"] = result.settings;
  if (film_settings.transparent || !film_settings.layers.empty() || rendered.contains("film"))
    rendered["film"] = {{"transparent", film_settings.transparent}, {"layers", film_settings.layers}};
  result.metadata = {
      {"nimbus/version", "0.1.0"},
      {"nimbus/integrator", settings.type},
      {"nimbus/spp", std::to_string(settings.spp)},
      {"nimbus/seed", std::to_string(settings.seed)},
      {"nimbus/max_events", std::to_string(settings.max_events)},
      {"nimbus/integrator_settings", result.settings.dump()},
      {"nimbus/scene_file", scene.file.string()},
      {"nimbus/scene", rendered.dump()},
      {"nimbus/partial", result.partial ? "true" : "false"},
      {"nimbus/render_seconds", fmt::format("{:.3f}", result.seconds)},
  };
  return result;
}

}  // namespace nimbus
