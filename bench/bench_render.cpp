// Whole-render throughput: samples per second of each integrator on a homogeneous sphere and on the
// Disney cloud, at 1 and 2 threads. Results go into docs/benchmarks.md.
#include <benchmark/benchmark.h>

#include <filesystem>

#include "nimbus/render.h"
#include "nimbus/scene.h"

namespace {

nimbus::Scene bench_scene(const std::string& name, int size) {
  nimbus::Scene s = nimbus::load_scene(std::filesystem::path(NIMBUS_SOURCE_DIR) / "scenes" / name);
  s.camera.width = size;
  s.camera.height = size * 3 / 4;
  return s;
}

void run(benchmark::State& state, const std::string& scene_file, const std::string& integrator, int spp) {
  const nimbus::Scene scene = bench_scene(scene_file, 64);
  nimbus::RenderOptions opt;
  opt.threads = int(state.range(0));
  opt.spp = spp;
  opt.integrator = integrator;
  int64_t samples = 0;
  for (auto _ : state) {
    const auto r = nimbus::render(scene, opt);
    benchmark::DoNotOptimize(r.image.rgb.data());
    samples += int64_t(scene.camera.width) * scene.camera.height * spp;
  }
  state.counters["samples/s"] = benchmark::Counter(double(samples), benchmark::Counter::kIsRate);
}

void BM_PathtraceSphere(benchmark::State& s) { run(s, "sphere_hg.json", "pathtrace", 4); }
void BM_PathtraceCloud(benchmark::State& s) { run(s, "disney_cloud.json", "pathtrace", 4); }
void BM_SingleSphere(benchmark::State& s) { run(s, "sphere_hg.json", "single", 1); }
void BM_SingleCloud(benchmark::State& s) { run(s, "disney_cloud.json", "single", 1); }

BENCHMARK(BM_PathtraceSphere)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_PathtraceCloud)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_SingleSphere)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_SingleCloud)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
