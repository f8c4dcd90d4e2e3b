// Volume grid micro-benchmarks: load time of the shared test volumes, and the cost of a density
// lookup through DensityGrid::density_index (a per-thread cached accessor, or the dense copy of a small
// grid) versus a per-thread Sampler, and the same through the tree alone (DensityGrid::without_dense).
#include <benchmark/benchmark.h>

#include <filesystem>
#include <random>

#include "io/vdb.h"

namespace {

using nimbus::DensityGrid;
using nimbus::load_density_grid;
using nimbus::Vec3;

std::filesystem::path volume(const char* name) {
  return std::filesystem::path(NIMBUS_SOURCE_DIR) / "../shared/data/volumes" / name;
}
const char* kFiles[] = {"wdas_cloud_sixteenth.vdb", "openvdb_fvdb_smoke-blosc.nvdb"};

void BM_Load(benchmark::State& state) {
  const auto file = volume(kFiles[state.range(0)]);
  double read = 0, analyse = 0;
  for (auto _ : state) {
    const DensityGrid g = load_density_grid(file);
    read += g.stats().read_seconds;
    analyse += g.stats().analyse_seconds;
  }
  state.counters["read_ms"] = 1e3 * read / state.iterations();
  state.counters["analyse_ms"] = 1e3 * analyse / state.iterations();
  state.SetLabel(kFiles[state.range(0)]);
}
BENCHMARK(BM_Load)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// Points along random short ray segments inside the bbox (coherent, like a tracker's lookups).
std::vector<Vec3> ray_points(const DensityGrid& g, size_t n) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec3> pts;
  const Vec3 lo = g.index_lo(), ext = g.index_hi() - g.index_lo();
  while (pts.size() < n) {
    Vec3 p(lo.x + u(rng) * ext.x, lo.y + u(rng) * ext.y, lo.z + u(rng) * ext.z);
    const Vec3 d = Vec3(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5).normalized() * 0.7;
    for (int i = 0; i < 32 && pts.size() < n; ++i) pts.push_back(p + d * double(i));
  }
  return pts;
}

void BM_DensityIndex(benchmark::State& state) {
  const DensityGrid g = load_density_grid(volume(kFiles[state.range(0)]));
  const auto pts = ray_points(g, 1 << 16);
  size_t i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(g.density_index(pts[i++ & 0xffff]));
  state.SetLabel(kFiles[state.range(0)]);
}
BENCHMARK(BM_DensityIndex)->Arg(0)->Arg(1);

void BM_SamplerDensity(benchmark::State& state) {
  const DensityGrid g = load_density_grid(volume(kFiles[state.range(0)]));
  const auto pts = ray_points(g, 1 << 16);
  DensityGrid::Sampler s(g);
  size_t i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(s.density_index(pts[i++ & 0xffff]));
  state.SetLabel(kFiles[state.range(0)]);
}
BENCHMARK(BM_SamplerDensity)->Arg(0)->Arg(1);

// The same lookups through the tree, as without the dense copy (the cloud has one; the smoke too).
void BM_TreeDensityIndex(benchmark::State& state) {
  const DensityGrid loaded = load_density_grid(volume(kFiles[state.range(0)]));
  const DensityGrid g = loaded.without_dense();
  const auto pts = ray_points(g, 1 << 16);
  size_t i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(g.density_index(pts[i++ & 0xffff]));
  state.SetLabel(kFiles[state.range(0)]);
}
BENCHMARK(BM_TreeDensityIndex)->Arg(0)->Arg(1);

void BM_TreeSamplerDensity(benchmark::State& state) {
  const DensityGrid loaded = load_density_grid(volume(kFiles[state.range(0)]));
  const DensityGrid g = loaded.without_dense();
  const auto pts = ray_points(g, 1 << 16);
  DensityGrid::Sampler s(g);
  size_t i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(s.density_index(pts[i++ & 0xffff]));
  state.SetLabel(kFiles[state.range(0)]);
}
BENCHMARK(BM_TreeSamplerDensity)->Arg(0)->Arg(1);

// Incoherent lookups (independent uniform points in the bbox), dense copy against the tree.
void BM_RandomDensityIndex(benchmark::State& state) {
  const DensityGrid loaded = load_density_grid(volume(kFiles[0]));
  const DensityGrid g = state.range(0) ? loaded : loaded.without_dense();
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec3> pts(1 << 16);
  const Vec3 lo = g.index_lo(), ext = g.index_hi() - g.index_lo();
  for (auto& p : pts) p = Vec3(lo.x + u(rng) * ext.x, lo.y + u(rng) * ext.y, lo.z + u(rng) * ext.z);
  size_t i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(g.density_index(pts[i++ & 0xffff]));
  state.SetLabel(state.range(0) ? "dense" : "tree");
}
BENCHMARK(BM_RandomDensityIndex)->Arg(0)->Arg(1);

void BM_MaxDensityIndex(benchmark::State& state) {
  const DensityGrid g = load_density_grid(volume(kFiles[0]));
  const auto pts = ray_points(g, 1 << 16);
  size_t i = 0;
  for (auto _ : state) {
    const Vec3 p = pts[i++ & 0xffff];
    benchmark::DoNotOptimize(g.max_density_index(p, p + Vec3(double(state.range(0)))));
  }
}
BENCHMARK(BM_MaxDensityIndex)->Arg(1)->Arg(8)->Arg(32);

}  // namespace

BENCHMARK_MAIN();
