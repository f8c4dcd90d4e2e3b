// The driver: resolves the render's settings, builds the scene context and the integrator through the
// registry, makes the camera rays and adds their radiance to the film, in passes over the whole image
// (1, 2, 4, ... spp), each tile by tile over oneTBB. Every sample is seeded from (seed, pixel, sample
// index) and added into the film's exact fixed-point sums (render/film.h), so the image is bit-identical
// for any thread count and for any split into passes or sample ranges: a render stopped (cancel, time
// budget) and resumed from its film state, or merged from ranges, equals the render made in one go.
// Progress and cancellation go through callbacks.
#include "nimbus/render.h"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <utility>

#include "integrators/registry.h"
#include "nimbus/error.h"
#include "render/adaptive.h"
#include "render/deep.h"
#include "render/film.h"
#include "render/film_layers.h"
#include "render/time_film.h"
#include "scene/edges.h"

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
    if (!settings.spp_given && !options.spp) settings.spp = default_spp(settings.type);
  }
  if (settings.spp < 1 || settings.spp > kMaxSpp)
    throw Error(fmt::format("spp must be between 1 and {}", kMaxSpp));
  if (options.threads < 0) throw Error("threads must be >= 0");
  if (options.tile_size < 1) throw Error("tile size must be >= 1");
  if (options.layers) check_film_layers(*options.layers);  // before any precomputation
  if (!(options.time_limit >= 0.0 && options.time_limit < 1e9)) throw Error("time limit must be >= 0 s");
  if (options.resume && options.deep_samples > 0) throw Error("a deep image cannot be resumed");
  if (!(options.noise >= 0.0 && options.noise < 1e3)) throw Error("noise target must be >= 0");
  if (options.noise > 0.0 && options.deep_samples > 0)
    throw Error("adaptive sampling (noise target) cannot make a deep image");
  if (options.noise_bin < 1 || options.noise_bin > 1024) throw Error("noise bin must be between 1 and 1024");
  if (options.noise > 0.0 && (options.region || options.sample_start != 0))
    throw Error(
        "adaptive sampling (noise target) plans its passes over the whole image and all its samples "
        "(no region, no sample range)");
  if (options.deep_samples > 0 && (options.region || options.sample_start != 0))
    throw Error("a deep image is made of the whole image and all its samples (no region, no sample range)");
  if (options.sample_start < 0 || int64_t(options.sample_start) + settings.spp > int64_t(kMaxSpp))
    throw Error(fmt::format("sample range: the first sample must be >= 0 and the last below {}", kMaxSpp));
  if (const auto& r = options.region; r && !(0 <= r->x0 && r->x0 < r->x1 && r->x1 <= scene.camera.width &&
                                             0 <= r->y0 && r->y0 < r->y1 && r->y1 <= scene.camera.height))
    throw Error(
        fmt::format("region {},{},{},{} is not a window inside the {}x{} image (x0,y0,x1,y1: "
                    "0 <= x0 < x1 <= width, 0 <= y0 < y1 <= height)",
                    r->x0, r->y0, r->x1, r->y1, scene.camera.width, scene.camera.height));
  if (options.deep_samples < 0 || options.deep_samples > kMaxDeepSamples)
    throw Error(fmt::format("deep samples must be between 1 and {} (0: no deep image)", kMaxDeepSamples));
  if (const auto& t = scene.film.time_bins; t && settings.type != "pathtrace")
    throw Error(fmt::format("film.time_bins: only the pathtrace integrator makes transient renders (not {})",
                            settings.type));
  if (scene.film.time_bins && options.resume)
    throw Error("film.time_bins: a transient render cannot be resumed (render it in one go)");
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
  int x0 = 0, y0 = 0;    // the film's first pixel in the image (a region)
  int sample_start = 0;  // sample s of a pass is sample sample_start + s of the pixel
  const FilmLayers& layers;
  int deep_samples = 0;                               // 0: no deep image
  std::vector<std::vector<DeepSample>>* deep_pixels;  // per pixel, when deep_samples > 0
  int adaptive_layer = -1;        // adaptive sampling: the film layer of kAdaptiveLayer (render/adaptive.h)
  TimeFilm* time_film = nullptr;  // a transient render (film.time_bins)
  // Per pixel of the window, row by row: the samples each of its pixel samples takes (k: pixel sample s
  // is samples k s .. k s + k - 1); null: 1 everywhere (Integrator::edge_samples, scene/edges.h).
  const std::vector<uint8_t>* sample_factor = nullptr;
  int factor(int x, int y) const {
    return sample_factor ? (*sample_factor)[size_t(y - y0) * size_t(film.width()) + size_t(x - x0)] : 1;
  }
};

// Positions in pixel (x, y): the R2 sequence rotated by the pixel's own random offset, drawn from the
// random stream `stream` of the pixel (render_pixel's comment says why).
struct PixelSequence {
  double ux, uy;
  PixelSequence(uint64_t seed, int x, int y, uint64_t stream) {
    Rng shift = Rng::for_sample(seed, uint32_t(x), uint32_t(y), stream);
    ux = shift.uniform();
    uy = shift.uniform();
  }
  // Sample s's position in the pixel, in [0, 1)^2.
  std::pair<double, double> at(int s) const {
    double jx = ux + s * kR2a1, jy = uy + s * kR2a2;
    return {jx - std::floor(jx), jy - std::floor(jy)};
  }
};

// Samples of pixel (x, y) into the film. Positions in the pixel: the R2 sequence (Roberts 2018), shifted
// by a random offset per pixel (a Cranley-Patterson rotation, so each sample is still uniform over the
// pixel and the estimate unbiased); its samples are spread evenly for every spp, which halves edge noise
// at a few spp. Pixel samples [s0, s1) of the pixel (its samples k s0 .. k s1 - 1, where it takes k per
// pixel sample: PixelTargets::sample_factor), added in order (a deep pixel takes all its samples in one
// call). Returns the number of non-finite samples (dropped).
int64_t render_pixel(const Integrator& integrator, const PinholeCamera& camera,
                     const IntegratorSettings& settings, int x, int y, int s0, int s1,
                     const PixelTargets& to) {
  const PixelSequence positions(settings.seed, x, y, ~uint64_t(0));
  int64_t bad = 0;
  thread_local std::vector<DeepSegment> segments, sample_segments;
  thread_local std::vector<TimedContribution> timed;
  segments.clear();
  const int k = to.factor(x, y);
  s0 = k * (s0 + to.sample_start);
  s1 = k * (s1 + to.sample_start);
  for (int s = s0; s < s1; ++s) {
    Rng rng = Rng::for_sample(settings.seed, uint32_t(x), uint32_t(y), uint64_t(s));
    const auto [jx, jy] = positions.at(s);
    CameraSample sample;
    sample.depth_wanted = to.layers.depth_wanted();
    sample_segments.clear();
    if (to.deep_samples > 0) sample.deep = &sample_segments;
    timed.clear();
    if (to.time_film) sample.timed = &timed;
    const Rgb L = integrator.Li(camera.generate_ray(x + jx, y + jy), rng, &sample);
    if (!to.layers.add(to.film, x - to.x0, y - to.y0, L, sample)) {
      ++bad;
      continue;  // a dropped sample adds nothing to the deep pixel (or the time bins) either
    }
    if (to.time_film) to.time_film->add(x - to.x0, y - to.y0, timed);
    segments.insert(segments.end(), sample_segments.begin(), sample_segments.end());
  }
  if (to.deep_samples > 0) {
    const size_t i = size_t(y) * size_t(to.film.width()) + size_t(x);
    merge_deep_segments(segments, 1.0 / (double(settings.spp) * k), to.deep_samples, &(*to.deep_pixels)[i]);
  }
  return bad;
}

// Adaptive sampling's probe samples [s0, s1) of pixel (x, y) into the adaptive layer (render/adaptive.h):
// drawn as the image's samples are, from a stream of random numbers the image's never use (and positions
// in the pixel rotated by an offset of their own), so that nothing the image takes decides its counts.
void render_probes(const Integrator& integrator, const PinholeCamera& camera,
                   const IntegratorSettings& settings, int x, int y, int s0, int s1, const PixelTargets& to) {
  const PixelSequence positions(settings.seed, x, y, kProbeIndexBase - 1);
  for (int s = s0; s < s1; ++s) {
    Rng rng = Rng::for_sample(settings.seed, uint32_t(x), uint32_t(y), kProbeIndexBase + uint64_t(s));
    const auto [jx, jy] = positions.at(s);
    CameraSample sample;
    sample.depth_wanted = to.layers.depth_wanted();
    const uint64_t rng_start = rng.state();
    const Rgb L = integrator.Li(camera.generate_ray(x + jx, y + jy), rng, &sample);
    // The luminance the film would take (less a transparent film's background); a non-finite one counts
    // as a dark sample, as it is dropped from the image.
    double lum = luminance(to.layers.beauty(L, sample));
    if (!std::isfinite(lum)) lum = 0.0;
    double a[kAdaptiveChannels];
    probe_values(lum, double(rng.draws_since(rng_start)), a);
    to.film.add(to.adaptive_layer, x - to.x0, y - to.y0, a);
  }
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

// Samples per pixel sample of each pixel of the window (Integrator::edge_samples at the pixels an outline
// crosses, a quarter of it beside them); empty where every pixel takes 1.
std::vector<uint8_t> sample_factors(const SceneContext& ctx, const Integrator& integrator,
                                    const Region& window) {
  const int n = std::min(integrator.edge_samples(), kMaxEdgeSamples);
  if (n <= 1) return {};
  const std::vector<PixelEdge> edges = edge_pixels(ctx, window);
  std::vector<uint8_t> k(edges.size(), 1);
  for (size_t i = 0; i < edges.size(); ++i)
    if (edges[i] != PixelEdge::none) k[i] = uint8_t(edges[i] == PixelEdge::outline ? n : std::max(1, n / 4));
  return k;
}

// A resumed film (not an adaptive one) must hold exactly the samples its `done` pixel samples gave each
// pixel (k of them per pixel sample at outline pixels): a state of an earlier nimbus, whose outline pixels
// took no more samples, or of another edge_samples would otherwise be continued from the wrong samples.
void check_resumed_counts(const Film& film, const std::vector<uint8_t>& factors, int done, const Region& w) {
  for (int y = 0; y < film.height(); ++y)
    for (int x = 0; x < film.width(); ++x) {
      const size_t i = size_t(y) * size_t(film.width()) + size_t(x);
      const int64_t want = int64_t(factors.empty() ? 1 : factors[i]) * done;
      if (int64_t(film.samples(x, y)) != want)
        throw Error(fmt::format(
            "resume: pixel ({}, {}) has {} samples where {} spp give it {} (an image of an earlier nimbus, "
            "whose pixels on a silhouette took no more samples, or of other edge_samples): render it again",
            x + w.x0, y + w.y0, film.samples(x, y), done, want));
    }
}

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// What every pass needs: the integrator and camera, the film's targets, the stop test, and the counts
// that progress reports over all passes.
struct PassContext {
  const Integrator& integrator;
  const PinholeCamera& camera;
  const IntegratorSettings& settings;
  const RenderOptions& options;
  const PixelTargets& targets;
  Region window;                 // the pixels rendered
  std::function<bool()> stop;    // cancelled, or past the time budget
  std::atomic<int64_t> done{0};  // pixel samples finished (over all passes)
  int64_t total = 0;             // pixel samples to take
  int64_t nonfinite = 0;         // in whole passes
  // Adaptive sampling: each pixel's sample count after the pass (its samples [count, target) are taken);
  // null: samples [s0, s1) of every pixel. And its probe samples' count after it.
  const std::vector<uint32_t>* target = nullptr;
  const std::vector<uint32_t>* probe = nullptr;
};

// Samples [s0, s1) of every pixel, tile by tile over oneTBB. Returns false when stopped part-way (the
// film then holds part of the pass).
bool render_pass(PassContext& pc, tbb::task_arena& arena, int s0, int s1) {
  const int ts = pc.options.tile_size, X0 = pc.window.x0, Y0 = pc.window.y0;
  const int W = pc.window.x1 - X0, H = pc.window.y1 - Y0;
  const int tiles_x = (W + ts - 1) / ts, tiles_y = (H + ts - 1) / ts;
  std::atomic<bool> stopped{false};
  std::atomic<int64_t> bad{0};
  auto render_tile = [&](int64_t tile) {
    const int x0 = X0 + int(tile % tiles_x) * ts, y0 = Y0 + int(tile / tiles_x) * ts;
    const int x1 = std::min(x0 + ts, X0 + W), y1 = std::min(y0 + ts, Y0 + H);
    int64_t tile_bad = 0, tile_samples = 0;
    for (int y = y0; y < y1; ++y) {
      // Stay responsive inside long tiles: the pass is abandoned.
      if (stopped.load(std::memory_order_relaxed) || pc.stop()) {
        stopped = true;
        return;
      }
      for (int x = x0; x < x1; ++x) {
        int a = s0, b = s1;
        if (pc.target) {
          const size_t i = size_t(y - Y0) * size_t(W) + size_t(x - X0);
          a = int(pc.targets.film.samples(x - X0, y - Y0));
          b = int((*pc.target)[i]);
          const int p0 = int(probe_count(pc.targets.film, pc.targets.adaptive_layer, x - X0, y - Y0));
          render_probes(pc.integrator, pc.camera, pc.settings, x, y, p0, int((*pc.probe)[i]), pc.targets);
        }
        tile_bad += render_pixel(pc.integrator, pc.camera, pc.settings, x, y, a, b, pc.targets);
        tile_samples += int64_t(b - a) * pc.targets.factor(x, y);
      }
    }
    bad += tile_bad;
    const int64_t done = pc.done += tile_samples;
    if (pc.options.progress) pc.options.progress(done, pc.total, done);
  };
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<int64_t>(0, int64_t(tiles_x) * tiles_y, 1),
                      [&](const tbb::blocked_range<int64_t>& r) {
                        for (int64_t t = r.begin(); t != r.end(); ++t) render_tile(t);
                      });
  });
  if (stopped) return false;
  pc.nonfinite += bad;
  return true;
}

// The header's record of how the image was made: the scene as rendered, with its integrator block
// replaced by the resolved one (overrides applied, "auto" choices made), and the spp reached.
ImageMetadata render_metadata(const Scene& scene, const RenderResult& result, const FilmSettings& film) {
  nlohmann::json rendered = scene.source.is_object() ? scene.source : nlohmann::json::object();
  rendered["integrator"] = result.settings;
  if (film.transparent || !film.layers.empty() || rendered.contains("film"))
    rendered["film"] = {{"transparent", film.transparent}, {"layers", film.layers}};
  if (const auto& t = film.time_bins) rendered["film"]["time_bins"] = {t->t0, t->t1, t->count};
  std::error_code ec;
  const std::filesystem::path file =
      scene.file.empty() ? scene.file : std::filesystem::absolute(scene.file, ec);
  return {
      {"nimbus/version", "0.1.0"},
      {"nimbus/integrator", result.integrator},
      {"nimbus/spp", std::to_string(result.spp)},
      {"nimbus/spp_requested", std::to_string(result.spp_requested)},
      {"nimbus/sample_start", std::to_string(result.sample_start)},
      {"nimbus/seed", std::to_string(result.seed)},
      {"nimbus/max_events", result.settings.value("max_events", nlohmann::json(0)).dump()},
      {"nimbus/integrator_settings", result.settings.dump()},
      {"nimbus/scene_file", ec ? scene.file.string() : file.string()},
      {"nimbus/scene", rendered.dump()},
      {"nimbus/partial", result.partial ? "true" : "false"},
      {"nimbus/time_limited", result.time_limited ? "true" : "false"},
      {"nimbus/render_seconds", fmt::format("{:.3f}", result.seconds)},
      {"nimbus/spp_mean", fmt::format("{:.3f}", result.spp_mean)},
      {"nimbus/noise_target", fmt::format("{}", result.noise_target)},
      {"nimbus/noise_estimate", fmt::format("{:.5f}", result.noise_estimate)},
  };
}

}  // namespace

int next_pass_spp(int done, int spp) {
  return std::min(spp, done < 1 ? 1 : (done > spp / 2 ? spp : 2 * done));
}

RenderResult render(const Scene& scene, const RenderOptions& options) {
  const auto start = Clock::now();
  const IntegratorSettings settings = resolve_settings(scene, options);

  // Every parallel part, the integrator's precomputation (shadow maps, photon grids) included, runs in
  // an arena of the requested size.
  const int threads = options.threads > 0 ? options.threads : tbb::this_task_arena::max_concurrency();
  tbb::task_arena arena(threads);
  std::optional<SceneContext> context;
  std::unique_ptr<Integrator> integrator;
  if (options.setup)
    options.setup(fmt::format("setting up {} (scene{})", settings.type,
                              settings.type == "pathtrace" ? "" : ", shadow maps, photon grids"));
  arena.execute([&] {
    context.emplace(scene);
    integrator = make_integrator(*context, settings, scene.file.empty() ? "scene" : scene.file.string());
  });

  RenderResult result;
  result.integrator = settings.type;
  result.spp_requested = settings.spp;
  result.seed = settings.seed;
  result.noise_target = options.noise;
  result.sample_start = options.sample_start;
  const Region window = options.region.value_or(Region{0, 0, scene.camera.width, scene.camera.height});
  const int W = window.x1 - window.x0, H = window.y1 - window.y0;
  Film film(W, H);
  FilmSettings film_settings = scene.film;
  if (options.layers) film_settings.layers = *options.layers;
  const FilmLayers layers(film, film_settings, context->has_environment);
  const bool adaptive = options.noise > 0.0;
  if (options.resume && std::any_of(options.resume->layers.begin(), options.resume->layers.end(),
                                    [](const FilmState::Layer& l) { return l.name == kAdaptiveLayerV1; }))
    throw Error(
        "resume: the image is an adaptive render of an earlier nimbus, whose passes its own samples "
        "decided; it cannot be continued (render it again)");
  const bool resumed_adaptive =
      options.resume && std::any_of(options.resume->layers.begin(), options.resume->layers.end(),
                                    [](const FilmState::Layer& l) { return l.name == kAdaptiveLayer; });
  if (adaptive && options.resume && !resumed_adaptive)
    throw Error("resume: adaptive sampling continues only a render made with a noise target");
  const int adaptive_layer = adaptive || resumed_adaptive
                                 ? film.add_layer(kAdaptiveLayer, kAdaptiveChannels, kAdaptiveFractionBits)
                                 : -1;
  int done = 0;
  if (options.resume) {
    film.restore(*options.resume);
    done = options.resume->spp;
    if (done > settings.spp && !adaptive)
      throw Error(
          fmt::format("resume: the image has {} spp, more than the {} asked for", done, settings.spp));
  }
  std::vector<std::vector<DeepSample>> deep_pixels(options.deep_samples > 0 ? size_t(W) * size_t(H) : 0);
  if (scene.film.time_bins && context->env_map)
    throw Error(
        "film.time_bins: an environment image is not supported in a transient render (constant "
        "environments, suns, point, spot and area lights are)");
  std::optional<TimeFilm> time_film;
  if (scene.film.time_bins) time_film.emplace(W, H, *scene.film.time_bins, film_settings.transparent);
  // Outline pixels take more samples (not in adaptive sampling, which gives each pixel its own count).
  std::vector<uint8_t> factors;
  if (adaptive_layer < 0) arena.execute([&] { factors = sample_factors(*context, *integrator, window); });
  if (options.resume && adaptive_layer < 0) check_resumed_counts(film, factors, done, window);
  const PixelTargets targets{film,
                             window.x0,
                             window.y0,
                             options.sample_start,
                             layers,
                             options.deep_samples,
                             &deep_pixels,
                             adaptive_layer,
                             time_film ? &*time_film : nullptr,
                             factors.empty() ? nullptr : &factors};
  int64_t factor_sum = int64_t(W) * H;  // samples per pixel sample over the window
  for (uint8_t k : factors) factor_sum += k - 1;

  bool first = true;
  auto cancelled = [&] { return options.cancel && options.cancel->load(std::memory_order_relaxed); };
  auto over_time = [&] {
    return options.time_limit > 0.0 && !first && seconds_since(start) > options.time_limit;
  };
  PassContext pc{*integrator,
                 context->camera,
                 settings,
                 options,
                 targets,
                 window,
                 [&] { return cancelled() || over_time(); }};
  pc.total = factor_sum * (settings.spp - done);
  const bool stoppable = options.cancel || options.time_limit > 0.0;
  double seconds_per_spp = 0.0;
  while (done < settings.spp && !adaptive) {
    int next = options.deep_samples > 0 ? settings.spp : next_pass_spp(done, settings.spp);
    if (!first && options.time_limit > 0.0) {  // only passes that fit the budget, as measured so far
      const double fit = 0.95 * (options.time_limit - seconds_since(start)) / seconds_per_spp;
      if (!(fit >= 1.0)) {
        result.time_limited = true;
        break;
      }
      next = int(std::min<double>(next, done + std::floor(fit)));
    }
    const FilmState before = stoppable ? film.state(done) : FilmState{};
    const std::optional<TimeFilm> time_before = stoppable ? time_film : std::nullopt;
    const auto pass_start = Clock::now();
    if (!render_pass(pc, arena, done, next)) {
      film.restore(before);
      if (time_before) time_film = time_before;  // the image of the last whole pass
      (cancelled() ? result.partial : result.time_limited) = true;
      break;
    }
    seconds_per_spp = seconds_since(pass_start) / (next - done);
    done = next;
    first = false;
  }
  if (done < settings.spp && !result.time_limited && !adaptive) result.partial = true;
  // Adaptive sampling: passes planned from the film's per-pixel variances (render/adaptive.h).
  const AdaptiveSettings adapt{options.noise, options.noise_bin, 0.05, std::min(8, settings.spp),
                               settings.spp};
  for (int pass = 1; adaptive; ++pass) {
    AdaptivePlan plan = plan_adaptive_pass(film, adaptive_layer, adapt);
    result.noise_estimate = plan.estimated_error;
    if (plan.new_samples == 0) break;
    const double per_sample = pass > 1 ? seconds_per_spp / (double(W) * H) : 0.0;
    const double new_work = double(plan.new_samples + plan.new_probes);
    if (!first && options.time_limit > 0.0 &&
        !(0.95 * (options.time_limit - seconds_since(start)) >= per_sample * new_work)) {
      result.time_limited = true;
      break;
    }
    if (options.setup && !first)
      options.setup(fmt::format("adaptive pass {}: noise {:.2f} % (target {:.2f} %)", pass,
                                100.0 * plan.estimated_error, 100.0 * options.noise));
    pc.target = &plan.target;
    pc.probe = &plan.probe;
    pc.total = pc.done + plan.new_samples;
    const FilmState before = stoppable ? film.state(done) : FilmState{};
    const std::optional<TimeFilm> time_before = stoppable ? time_film : std::nullopt;
    const auto pass_start = Clock::now();
    if (!render_pass(pc, arena, 0, 0)) {
      film.restore(before);
      if (time_before) time_film = time_before;
      (cancelled() ? result.partial : result.time_limited) = true;
      break;
    }
    seconds_per_spp = seconds_since(pass_start) / new_work * (double(W) * H);  // per sample, probes included
    first = false;
  }
  double count_sum = 0.0;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      count_sum += film.samples(x, y);
      if (adaptive) done = std::max(done, int(film.samples(x, y)));
    }
  result.spp_mean = count_sum / (double(W) * H);

  result.spp = done;
  result.image = layers.resolve(film);
  if (options.region) {
    result.image.origin_x = window.x0;
    result.image.origin_y = window.y0;
    result.image.display_width = scene.camera.width;
    result.image.display_height = scene.camera.height;
  }
  if (options.deep_samples > 0 && done == settings.spp) result.deep = assemble_deep(W, H, deep_pixels);
  result.nonfinite_samples = pc.nonfinite;
  result.seconds = seconds_since(start);
  result.settings = resolved_block(settings, *integrator);
  result.metadata = render_metadata(scene, result, film_settings);
  if (time_film) {  // the steady image with the time bins as layers (render/time_film.h)
    for (auto& kv : time_film->metadata()) result.metadata.push_back(kv);
    result.transient = result.image;
    result.transient.channels = time_film->resolve(film);
  }
  if (options.deep_samples == 0) result.state = std::move(film).take_state(done);  // the film's last use
  if (options.region)
    result.metadata.emplace_back("nimbus/region",
                                 fmt::format("{},{},{},{}", window.x0, window.y0, window.x1, window.y1));
  return result;
}

}  // namespace nimbus
