// The tile driver: tiles over oneTBB, every sample seeded from (seed, pixel, sample index) so the
// image is bit-identical for any thread count; progress and cancellation through callbacks.
#include "nimbus/render.h"

#include <chrono>
#include <cmath>
#include <memory>
#include <optional>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "integrators/integrator.h"
#include "nimbus/error.h"

namespace nimbus {

namespace {
// The R2 sequence's steps: 1 / p and 1 / p^2 for the plastic number p = 1.3247179572...
constexpr double kR2a1 = 0.75487766624669276, kR2a2 = 0.56984029099805327;
}  // namespace

std::vector<std::string> integrator_names() { return {"pathtrace", "single", "mfs", "octave"}; }

RenderResult render(const Scene& scene, const RenderOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  IntegratorSettings settings = scene.integrator;
  if (options.spp) settings.spp = *options.spp;
  if (options.seed) settings.seed = *options.seed;
  if (options.integrator) settings.type = *options.integrator;
  if (settings.spp < 1 || settings.spp > kMaxSpp)
    throw Error(fmt::format("spp must be between 1 and {}", kMaxSpp));
  if (options.threads < 0) throw Error("threads must be >= 0");
  if (options.tile_size < 1) throw Error("tile size must be >= 1");

  // Every parallel part, the integrator's precomputation (shadow maps, photon grids) included, runs in
  // an arena of the requested size.
  const int threads = options.threads > 0 ? options.threads : tbb::this_task_arena::max_concurrency();
  tbb::task_arena arena(threads);
  std::optional<SceneContext> context_storage;
  std::unique_ptr<Integrator> integrator;
  arena.execute([&] {
    context_storage.emplace(scene);
    integrator = make_integrator(settings.type, settings, *context_storage);
  });

  RenderResult result;
  result.integrator = settings.type;
  result.spp = settings.spp;
  result.seed = settings.seed;
  const int W = scene.camera.width, H = scene.camera.height, ts = options.tile_size;
  result.image = Image(W, H);
  const int tiles_x = (W + ts - 1) / ts, tiles_y = (H + ts - 1) / ts;
  result.tiles_total = int64_t(tiles_x) * tiles_y;

  std::atomic<int64_t> tiles_done{0}, nonfinite{0}, samples{0};
  std::atomic<bool> stopped{false};
  auto render_tile = [&](int64_t tile) {
    if (options.cancel && options.cancel->load(std::memory_order_relaxed)) {
      stopped = true;
      return;
    }
    const int x0 = int(tile % tiles_x) * ts, y0 = int(tile / tiles_x) * ts;
    int64_t bad = 0;
    for (int y = y0; y < std::min(y0 + ts, H); ++y) {
      // Stay responsive inside long tiles: abandon the tile (it counts as not done).
      if (options.cancel && options.cancel->load(std::memory_order_relaxed)) {
        stopped = true;
        nonfinite += bad;
        return;
      }
      for (int x = x0; x < std::min(x0 + ts, W); ++x) {
        Rgb sum(0.0);
        // Positions in the pixel: the R2 sequence (Roberts 2018), shifted by a random offset per pixel
        // (a Cranley-Patterson rotation, so each sample is still uniform over the pixel and the estimate
        // unbiased); its samples are spread evenly for every spp, which halves edge noise at a few spp.
        Rng shift = Rng::for_sample(settings.seed, uint32_t(x), uint32_t(y), ~uint64_t(0));
        const double ux = shift.uniform(), uy = shift.uniform();
        for (int s = 0; s < settings.spp; ++s) {
          Rng rng = Rng::for_sample(settings.seed, uint32_t(x), uint32_t(y), uint64_t(s));
          double jx = ux + s * kR2a1, jy = uy + s * kR2a2;
          jx -= std::floor(jx);
          jy -= std::floor(jy);
          const Rgb L = integrator->sample(x + jx, y + jy, rng);
          if (is_finite(L)) {
            sum += L;
          } else {
            ++bad;
          }
        }
        float* px = result.image.pixel(x, y);
        for (int c = 0; c < 3; ++c) px[c] = float(sum[c] / settings.spp);
      }
    }
    nonfinite += bad;
    const int64_t n = int64_t(std::min(x0 + ts, W) - x0) * (std::min(y0 + ts, H) - y0) * settings.spp;
    const int64_t done = ++tiles_done;
    const int64_t total_samples = samples += n;
    if (options.progress) options.progress(done, result.tiles_total, total_samples);
  };

  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<int64_t>(0, result.tiles_total, 1),
                      [&](const tbb::blocked_range<int64_t>& r) {
                        for (int64_t t = r.begin(); t != r.end(); ++t) render_tile(t);
                      });
  });

  result.tiles_done = tiles_done;
  result.partial = stopped || tiles_done < result.tiles_total;
  result.nonfinite_samples = nonfinite;
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  result.metadata = {
      {"nimbus/version", "0.1.0"},
      {"nimbus/integrator", settings.type},
      {"nimbus/spp", std::to_string(settings.spp)},
      {"nimbus/seed", std::to_string(settings.seed)},
      {"nimbus/max_events", std::to_string(settings.max_events)},
      {"nimbus/scene_file", scene.file.string()},
      {"nimbus/scene", scene.source.dump()},
      {"nimbus/partial", result.partial ? "true" : "false"},
      {"nimbus/render_seconds", fmt::format("{:.3f}", result.seconds)},
  };
  return result;
}

}  // namespace nimbus
