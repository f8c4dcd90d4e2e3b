// Surfaces (issue 10): loading a 1M-triangle OBJ mesh (the file read, tinyobjloader's parse alone, and
// load_mesh whole: nimbus's line checks, tinyobjloader, de-indexing and triangle checks), building its
// Embree BVH (the SceneSurfaces constructor), and rays per second of intersect and occluded on it.
// The mesh is a displaced 708 x 708 grid (501 264 vertices, 999 698 triangles), written into a
// temporary folder when the program starts, with and without vertex normals (Arg 0 / 1), and removed
// at exit. Results go into docs/benchmarks.md.
#include <benchmark/benchmark.h>
#include <tiny_obj_loader.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "core/rng.h"
#include "io/mesh.h"
#include "scene/surfaces.h"

namespace {

namespace fs = std::filesystem;

constexpr int kGrid = 708;  // vertices per side: 708^2 = 501 264 vertices, 2 * 707^2 = 999 698 triangles

// A height field z = h(x, y) over [-1, 1]^2 in OBJ text, with analytic normals when asked.
void write_grid(const fs::path& file, bool with_normals) {
  std::FILE* f = std::fopen(file.c_str(), "w");
  if (!f) throw std::runtime_error("cannot write " + file.string());
  const auto h = [](double x, double y) { return 0.1 * std::sin(7.0 * x) * std::cos(5.0 * y); };
  for (int j = 0; j < kGrid; ++j)
    for (int i = 0; i < kGrid; ++i) {
      const double x = -1.0 + 2.0 * i / (kGrid - 1), y = -1.0 + 2.0 * j / (kGrid - 1);
      std::fprintf(f, "v %.6f %.6f %.6f\n", x, y, h(x, y));
    }
  if (with_normals)
    for (int j = 0; j < kGrid; ++j)
      for (int i = 0; i < kGrid; ++i) {
        const double x = -1.0 + 2.0 * i / (kGrid - 1), y = -1.0 + 2.0 * j / (kGrid - 1);
        const double hx = 0.7 * std::cos(7.0 * x) * std::cos(5.0 * y);
        const double hy = -0.5 * std::sin(7.0 * x) * std::sin(5.0 * y);
        const double len = std::sqrt(hx * hx + hy * hy + 1.0);
        std::fprintf(f, "vn %.6f %.6f %.6f\n", -hx / len, -hy / len, 1.0 / len);
      }
  for (int j = 0; j + 1 < kGrid; ++j)
    for (int i = 0; i + 1 < kGrid; ++i) {
      const int a = j * kGrid + i + 1, b = a + 1, c = a + kGrid, d = c + 1;  // 1-based
      if (with_normals) {
        std::fprintf(f, "f %d//%d %d//%d %d//%d\n", a, a, b, b, d, d);
        std::fprintf(f, "f %d//%d %d//%d %d//%d\n", a, a, d, d, c, c);
      } else {
        std::fprintf(f, "f %d %d %d\nf %d %d %d\n", a, b, d, a, d, c);
      }
    }
  std::fclose(f);
}

// The two files, written once, removed at exit.
struct Files {
  fs::path dir;
  fs::path grid[2];
  Files() {
    dir = fs::temp_directory_path() / ("nimbus_bench_surfaces_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    for (int n = 0; n < 2; ++n) {
      grid[n] = dir / (n ? "grid_normals.obj" : "grid.obj");
      write_grid(grid[n], n == 1);
    }
  }
  ~Files() {
    std::error_code ec;
    fs::remove_all(dir, ec);
  }
};

const Files& files() {
  static const Files f;
  return f;
}

std::string read_text(const fs::path& file) {  // as load_mesh reads it: one sized read
  std::ifstream in(file, std::ios::binary | std::ios::ate);
  std::string text(size_t(in.tellg()), '\0');
  in.seekg(0);
  in.read(text.data(), std::streamsize(text.size()));
  return text;
}

void set_file_counters(benchmark::State& state, const fs::path& file) {
  state.counters["MB"] = double(fs::file_size(file)) / 1e6;
}

// The file into memory, as load_mesh reads it.
void BM_ObjRead(benchmark::State& state) {
  const fs::path& file = files().grid[state.range(0)];
  for (auto _ : state) benchmark::DoNotOptimize(read_text(file).size());
  set_file_counters(state, file);
}

// tinyobjloader's parse of the text alone, configured as mesh_from_obj_text configures it.
void BM_ObjTinyobjParse(benchmark::State& state) {
  const std::string text = read_text(files().grid[state.range(0)]);
  for (auto _ : state) {
    tinyobj::ObjReaderConfig config;
    config.triangulate = true;
    config.vertex_color = false;
    tinyobj::ObjReader reader;
    if (!reader.ParseFromString(text, "", config)) state.SkipWithError("parse failed");
    benchmark::DoNotOptimize(reader.GetAttrib().vertices.data());
  }
}

// mesh_from_obj_text: nimbus's line checks + tinyobjloader + de-indexing + triangle checks.
void BM_ObjMeshFromText(benchmark::State& state) {
  const std::string text = read_text(files().grid[state.range(0)]);
  size_t triangles = 0;
  for (auto _ : state) triangles = nimbus::mesh_from_obj_text(text, "grid.obj").triangle_count();
  state.counters["triangles"] = double(triangles);
}

// load_mesh whole: read + mesh_from_obj_text.
void BM_LoadMesh(benchmark::State& state) {
  const fs::path& file = files().grid[state.range(0)];
  size_t vertices = 0;
  for (auto _ : state) vertices = nimbus::load_mesh(file, "grid.obj")->vertex_count();
  state.counters["vertices"] = double(vertices);
  set_file_counters(state, file);
}

std::shared_ptr<const nimbus::TriangleMesh> mesh(int with_normals) {
  static std::shared_ptr<const nimbus::TriangleMesh> m[2];
  if (!m[with_normals]) m[with_normals] = nimbus::load_mesh(files().grid[with_normals], "grid.obj");
  return m[with_normals];
}

std::vector<nimbus::Surface> surfaces(int with_normals) {
  nimbus::Surface s;
  s.shape = nimbus::MeshSurface{"grid.obj", mesh(with_normals)};
  return {s};
}

// The Embree BVH: SceneSurfaces' constructor (the mesh carried into the world, the Embree scene built).
void BM_BuildBvh(benchmark::State& state) {
  const std::vector<nimbus::Surface> s = surfaces(int(state.range(0)));
  for (auto _ : state) {
    nimbus::SceneSurfaces scene(s);
    benchmark::DoNotOptimize(scene.bounds());
  }
}

// Random rays through the mesh's bounds: origins on a sphere twice the bounds' diagonal away from
// their centre, directions to a uniform point inside the bounds; about 92 % hit the grid.
struct Rays {
  std::vector<nimbus::Vec3> o, d;
};
Rays random_rays(const nimbus::Bounds& b, int n) {
  nimbus::Rng rng(7, 0);
  const nimbus::Vec3 c = (b.lo + b.hi) * 0.5, size = b.hi - b.lo;
  const double r = 2.0 * size.length();
  Rays rays;
  for (int k = 0; k < n; ++k) {
    const double z = 2.0 * rng.uniform() - 1.0, phi = 2.0 * M_PI * rng.uniform();
    const double s = std::sqrt(std::max(0.0, 1.0 - z * z));
    const nimbus::Vec3 o = c + nimbus::Vec3(s * std::cos(phi), s * std::sin(phi), z) * r;
    const nimbus::Vec3 target =
        b.lo + nimbus::Vec3(size.x * rng.uniform(), size.y * rng.uniform(), size.z * rng.uniform());
    rays.o.push_back(o);
    rays.d.push_back(nimbus::normalize(target - o));
  }
  return rays;
}

template <bool kOccluded>
void rays(benchmark::State& state) {
  const std::vector<nimbus::Surface> s = surfaces(int(state.range(0)));
  const nimbus::SceneSurfaces scene(s);
  const Rays r = random_rays(scene.bounds(), 1 << 16);
  int64_t traced = 0, hits = 0;
  for (auto _ : state) {
    for (size_t k = 0; k < r.o.size(); ++k) {
      bool hit;
      if constexpr (kOccluded) {
        hit = scene.occluded(r.o[k], r.d[k], 1e30);
      } else {
        nimbus::SurfaceHit h;
        hit = scene.intersect(r.o[k], r.d[k], 1e30, &h);
      }
      hits += hit;
    }
    traced += int64_t(r.o.size());
  }
  state.counters["rays/s"] = benchmark::Counter(double(traced), benchmark::Counter::kIsRate);
  state.counters["hit fraction"] = double(hits) / double(traced);
}
void BM_Intersect(benchmark::State& state) { rays<false>(state); }
void BM_Occluded(benchmark::State& state) { rays<true>(state); }

BENCHMARK(BM_ObjRead)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK(BM_ObjTinyobjParse)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK(BM_ObjMeshFromText)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK(BM_LoadMesh)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK(BM_BuildBvh)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK(BM_Intersect)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_Occluded)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
