// The per-pixel cost of `mfs` (issue 12), apart from its set-up:
//  - BM_MfsPixelSetup: the scene context and the integrator's precomputation (shadow maps, beam and scatter
//    grids), the scene file already loaded;
//  - BM_MfsPixelMarch: every camera ray of the image once (pixel centres, 1 spp) through Li with the
//    integrator built once, on 1 or 2 threads. Counters: ns per march step (thread time: wall x threads over
//    the steps), steps per camera ray that meets the medium (mean, standard deviation, median, 90th
//    percentile, maximum; from the per-thread step counter mfs_march_steps of integrators/mfs.h), ns per
//    such ray;
//  - BM_MfsPixelSkeleton: the same rays through the bare march (march_growing with the media's
//    extinction and the camera-side state, no lights, no grids; over the pieces of constant-density
//    shapes, as `mfs`): the floor that the light estimators sit on.
// range(0) picks the scene (kScenes), range(1) the image width (height from the scene's aspect), range(2)
// the threads. The integrator's options: the defaults, or those in $NIMBUS_BENCH_MFS (a JSON object). Results: docs/benchmarks.md, "Per-pixel cost of mfs and the 1080p cloud".
#include <benchmark/benchmark.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <map>
#include <memory>
#include <numeric>

#include "integrators/mfs.h"
#include "integrators/tracking.h"
#include "nimbus/scene.h"
#include "scene/context.h"

namespace {

using namespace nimbus;

// The scenes: the Disney cloud (sun + sky) and the dense homogeneous sphere (optical radius 10, HG 0.85,
// sun + sky).
const char* const kScenes[] = {"disney_cloud.json", "sphere_hg.json"};

Scene load(int scene, int width) {
  Scene s = load_scene(std::filesystem::path(NIMBUS_SOURCE_DIR) / "scenes" / kScenes[scene]);
  const double aspect = double(s.camera.height) / s.camera.width;
  s.camera.width = width;
  s.camera.height = std::max(1, int(std::lround(width * aspect)));
  return s;
}

// The integrator's options: the defaults, or the JSON object in $NIMBUS_BENCH_MFS (e.g. '{"tau_step": 0.1}').
const nlohmann::json kMfs = std::getenv("NIMBUS_BENCH_MFS")
                                ? nlohmann::json::parse(std::getenv("NIMBUS_BENCH_MFS"))
                                : nlohmann::json::object();

// A scene with its context and integrator, built once per (scene, width) and kept for the process.
struct Prepared {
  Scene scene;
  std::unique_ptr<SceneContext> ctx;
  std::unique_ptr<MfsIntegrator> mfs;
};

Prepared& prepared(int scene, int width) {
  static std::map<std::pair<int, int>, Prepared> cache;
  Prepared& p = cache[{scene, width}];
  if (!p.mfs) {
    p.scene = load(scene, width);
    p.ctx = std::make_unique<SceneContext>(p.scene);
    p.mfs = std::make_unique<MfsIntegrator>(*p.ctx, mfs_settings_from_json(kMfs, "bench"),
                                            p.scene.integrator.seed);
  }
  return p;
}

// Every pixel's camera ray (through its centre) on `threads` threads; f(ray, rng) -> steps of that ray.
// Returns the steps per pixel.
template <typename F>
std::vector<uint32_t> each_pixel(const Scene& scene, int threads, F&& f) {
  const int W = scene.camera.width, H = scene.camera.height;
  const PinholeCamera camera(scene.camera);
  std::vector<uint32_t> steps(size_t(W) * H);
  tbb::task_arena arena(threads);
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<int>(0, H, 1), [&](const tbb::blocked_range<int>& rows) {
      for (int y = rows.begin(); y < rows.end(); ++y)
        for (int x = 0; x < W; ++x) {
          Rng rng = Rng::for_sample(scene.integrator.seed, uint32_t(x), uint32_t(y), 0);
          steps[size_t(y) * W + x] = f(camera.generate_ray(x + 0.5, y + 0.5), rng);
        }
    });
  });
  return steps;
}

// Steps per ray over the rays that took any, as counters.
void step_counters(benchmark::State& state, const std::vector<uint32_t>& steps, double seconds, double cpu,
                   int threads) {
  std::vector<uint32_t> hit;
  for (uint32_t s : steps)
    if (s > 0) hit.push_back(s);
  std::sort(hit.begin(), hit.end());
  const double n = double(std::max<size_t>(1, hit.size()));
  const double total = std::accumulate(hit.begin(), hit.end(), 0.0);
  double sq = 0.0;
  for (uint32_t s : hit) sq += double(s) * s;
  const double mean = total / n;
  state.counters["rays"] = double(steps.size());
  state.counters["hit_rays"] = double(hit.size());
  state.counters["steps_mean"] = mean;
  state.counters["steps_sd"] = std::sqrt(std::max(0.0, sq / n - mean * mean));
  state.counters["steps_p50"] = hit.empty() ? 0.0 : hit[hit.size() / 2];
  state.counters["steps_p90"] = hit.empty() ? 0.0 : hit[hit.size() * 9 / 10];
  state.counters["steps_max"] = hit.empty() ? 0.0 : hit.back();
  state.counters["ns_per_step"] = seconds * threads * 1e9 / std::max(1.0, total);
  state.counters["ns_per_hit_ray"] = seconds * threads * 1e9 / n;
  state.counters["cpu_ns_per_step"] = cpu * 1e9 / std::max(1.0, total);
}

using Clock = std::chrono::steady_clock;

// CPU seconds of the whole process (every thread): on a loaded machine a steadier measure than wall time.
double process_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

void BM_MfsPixelSetup(benchmark::State& state) {
  const Scene scene = load(int(state.range(0)), int(state.range(1)));
  tbb::task_arena arena(int(state.range(2)));
  for (auto _ : state) {
    arena.execute([&] {
      const SceneContext ctx(scene);
      const MfsIntegrator mfs(ctx, mfs_settings_from_json(kMfs, "bench"), scene.integrator.seed);
      benchmark::DoNotOptimize(mfs.memory_bytes());
    });
  }
}

void BM_MfsPixelMarch(benchmark::State& state) {
  const Prepared& p = prepared(int(state.range(0)), int(state.range(1)));
  const int threads = int(state.range(2));
  std::vector<uint32_t> steps;
  double seconds = 0.0, cpu = 0.0;
  for (auto _ : state) {
    const auto t0 = Clock::now();
    const double c0 = process_cpu_seconds();
    steps = each_pixel(p.scene, threads, [&](const Ray& ray, Rng& rng) {
      const uint64_t before = mfs_march_steps;
      CameraSample sample;
      benchmark::DoNotOptimize(p.mfs->Li(ray, rng, &sample));
      return uint32_t(mfs_march_steps - before);
    });
    seconds += std::chrono::duration<double>(Clock::now() - t0).count();
    cpu += process_cpu_seconds() - c0;
  }
  step_counters(state, steps, seconds / double(state.iterations()), cpu / double(state.iterations()),
                threads);
}

void BM_MfsPixelSkeleton(benchmark::State& state) {
  const Prepared& p = prepared(int(state.range(0)), int(state.range(1)));
  const SceneContext& ctx = *p.ctx;
  const MfsSettings s = mfs_settings_from_json(kMfs, "bench");
  std::vector<double> f, theta2;
  for (int i = 0; i < ctx.media.count(); ++i)
    f.push_back(p.mfs->split(i).f()), theta2.push_back(p.mfs->split(i).theta2());
  std::vector<uint32_t> steps;
  double seconds = 0.0, cpu = 0.0;
  for (auto _ : state) {
    const auto t0 = Clock::now();
    const double c0 = process_cpu_seconds();
    steps = each_pixel(p.scene, 1, [&](const Ray& ray, Rng& rng) {
      CameraPath cam;
      MediumPoint mp;
      const double jitter = rng.uniform();
      uint32_t n = 0;
      const auto scale = [&](double, double) { return 1.0 + s.step_growth * max_component(cam.tau_red); };
      const auto step = [&](const Vec3& q, double t, double dt, double u) {
        ++n;
        ctx.media.eval(q, &mp);
        cam.advance(mfs_extinction(mp, f, theta2), t, dt, u);
        return max_component(cam.T_red) > 1e-6;
      };
      const double inf = std::numeric_limits<double>::infinity();
      if (ctx.analytic.active())  // as MfsIntegrator::trace: over the pieces of constant-density shapes
        march_growing(ctx.analytic, ray.o, ray.d, inf, s.tau_step, p.mfs->max_step(), jitter, scale, step);
      else
        march_growing(ctx.majorants, ray.o, ray.d, inf, s.tau_step, jitter, scale, step);
      benchmark::DoNotOptimize(cam.T_red);
      return n;
    });
    seconds += std::chrono::duration<double>(Clock::now() - t0).count();
    cpu += process_cpu_seconds() - c0;
  }
  step_counters(state, steps, seconds / double(state.iterations()), cpu / double(state.iterations()), 1);
}

BENCHMARK(BM_MfsPixelSetup)->Args({0, 4, 1})->Args({1, 4, 1})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_MfsPixelMarch)
    ->Args({0, 160, 1})
    ->Args({0, 160, 2})
    ->Args({1, 128, 1})
    ->Args({1, 128, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_MfsPixelSkeleton)
    ->Args({0, 160, 1})
    ->Args({1, 128, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
