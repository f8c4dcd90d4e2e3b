// `mfs` against `single` (the goal: multiple scattering for at most twice single scattering's
// cost): whole renders of the Disney cloud and the dense sphere at several image sizes and thread
// counts, the precomputation alone (a 4 x 3 image) against its grid resolution and photon count, and
// the memory of the precomputed grids. Results go into docs/benchmarks.md.
#include <benchmark/benchmark.h>

#include <filesystem>

#include "integrators/mfs.h"
#include "integrators/registry.h"
#include "nimbus/render.h"
#include "nimbus/scene.h"

namespace {

nimbus::Scene scene_with(const std::string& file, const nlohmann::json& integrator, int width) {
  nimbus::Scene s = nimbus::load_scene(std::filesystem::path(NIMBUS_SOURCE_DIR) / "scenes" / file);
  s.camera.width = width;
  s.camera.height = std::max(1, width * 3 / 4);
  s.integrator.type = integrator.at("type").get<std::string>();
  s.integrator.spp = 1;
  s.integrator.options = integrator;
  s.integrator.options.erase("type");
  return s;
}

void run(benchmark::State& state, const std::string& file, const nlohmann::json& integrator, int width,
         int threads) {
  const nimbus::Scene scene = scene_with(file, integrator, width);
  nimbus::RenderOptions opt;
  opt.threads = threads;
  for (auto _ : state) {
    const auto r = nimbus::render(scene, opt);
    benchmark::DoNotOptimize(r.image.rgb.data());
  }
  state.counters["pixels"] = double(scene.camera.width) * scene.camera.height;
}

const nlohmann::json kSingle = {{"type", "single"}};  // ratio-tracked shadow rays
const nlohmann::json kSingleMap = {
    {"type", "single"}, {"transmittance", "shadow_map"}, {"shadow_map_resolution", 64}};
const nlohmann::json kMfs = {{"type", "mfs"}};
const nlohmann::json kMfsK1 = {{"type", "mfs"}, {"large_angle_scatters", 1}};

// Whole renders: range(0) = image width, range(1) = threads.
void BM_SingleCloud(benchmark::State& s) {
  run(s, "disney_cloud.json", kSingle, int(s.range(0)), int(s.range(1)));
}
void BM_MfsCloud(benchmark::State& s) { run(s, "disney_cloud.json", kMfs, int(s.range(0)), int(s.range(1))); }
void BM_MfsK1Cloud(benchmark::State& s) {
  run(s, "disney_cloud.json", kMfsK1, int(s.range(0)), int(s.range(1)));
}
void BM_SingleSphere(benchmark::State& s) {
  run(s, "sphere_hg.json", kSingle, int(s.range(0)), int(s.range(1)));
}
void BM_MfsSphere(benchmark::State& s) { run(s, "sphere_hg.json", kMfs, int(s.range(0)), int(s.range(1))); }

// The precomputation of mfs on the cloud (shadow maps + photon grid) on a 4 x 3 image:
// range(0) = scatter grid resolution, range(1) = photons.
void BM_MfsCloudPrecompute(benchmark::State& s) {
  nlohmann::json cfg = kMfs;
  cfg["scatter_grid_resolution"] = s.range(0);
  cfg["photons"] = s.range(1);
  run(s, "disney_cloud.json", cfg, 4, 0);
}

// The parts of the precomputation on the cloud (4 x 3 image, 2 threads), added one at a time:
// range(0) = 0: scene set-up, phase-split tables and shadow maps (K = 1, no beam grid); 1: + the beam
// grid (default photons); 2: + the scatter grid (the default mfs).
void BM_MfsCloudSetupParts(benchmark::State& s) {
  nlohmann::json cfg = kMfs;
  if (s.range(0) < 2) cfg["large_angle_scatters"] = 1;
  if (s.range(0) < 1) cfg["beam_photons"] = 0;
  run(s, "disney_cloud.json", cfg, 4, 2);
}

// Memory of the precomputed grids (reported as counters; the timing is the construction).
void BM_MfsCloudMemory(benchmark::State& state) {
  const nimbus::Scene scene = scene_with("disney_cloud.json", kMfs, 4);
  const nimbus::SceneContext ctx(scene);
  size_t grid_bytes = 0, beam_bytes = 0, total_bytes = 0;
  for (auto _ : state) {
    const nimbus::MfsIntegrator mfs(ctx, nimbus::mfs_settings_from_json(scene.integrator.options, "bench"));
    grid_bytes = mfs.scatter_grid()->memory_bytes();
    beam_bytes = mfs.beam_grid() ? mfs.beam_grid()->memory_bytes() : 0;
    total_bytes = mfs.memory_bytes();
    benchmark::DoNotOptimize(grid_bytes);
  }
  state.counters["scatter_grid_MB"] = double(grid_bytes) / 1e6;
  state.counters["beam_grid_MB"] = double(beam_bytes) / 1e6;
  state.counters["all_grids_MB"] = double(total_bytes) / 1e6;
}

BENCHMARK(BM_SingleCloud)
    ->Args({64, 2})
    ->Args({128, 2})
    ->Args({256, 2})
    ->Args({128, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_MfsK1Cloud)
    ->Args({64, 2})
    ->Args({128, 2})
    ->Args({256, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_MfsCloud)
    ->Args({64, 2})
    ->Args({128, 2})
    ->Args({256, 2})
    ->Args({128, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_SingleSphere)->Args({128, 2})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_MfsSphere)->Args({128, 2})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_MfsCloudPrecompute)
    ->Args({16, 1 << 18})
    ->Args({32, 1 << 18})
    ->Args({64, 1 << 18})
    ->Args({32, 1 << 16})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_MfsCloudSetupParts)->DenseRange(0, 2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_MfsCloudMemory)->Iterations(1)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
