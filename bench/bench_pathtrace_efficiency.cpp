// The path tracer's efficiency on the suite's homogeneous HG spheres (issue 12): efficiency =
// 1 / (variance per sample x time per sample). Each scene is rendered K times with independent seeds;
// the per-pixel sample variance across the K images times their spp is the per-sample variance, averaged
// over pixels and channels; the time per sample is the renders' CPU time (the process's, all threads) over
// their samples, which other jobs on a shared machine disturb less than the wall time.
// Results go into docs/benchmarks.md ("The judge's efficiency").
//
//   build/bin/bench_pathtrace_efficiency [spp = 16] [K = 8] [threads = 1]
#include <time.h>

#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "nimbus/render.h"
#include "nimbus/scene.h"

namespace {

// The unit sphere of optical radius tau seen from 4 units (validation/mfs_validation.py: homogeneous()).
nimbus::Scene sphere(double tau, double albedo, double g, const std::vector<double>& light) {
  nlohmann::json doc = {{"camera",
                         {{"position", {0, -4, 0}},
                          {"look_at", {0, 0, 0}},
                          {"up", {0, 0, 1}},
                          {"fov_y_deg", 35},
                          {"width", 48},
                          {"height", 48}}},
                        {"media",
                         {{{"shape", {{"type", "sphere"}, {"center", {0, 0, 0}}, {"radius", 1}}},
                           {"sigma_s", albedo * tau},
                           {"sigma_a", (1 - albedo) * tau},
                           {"phase", {{"type", "hg"}, {"g", g}}}}}},
                        {"lights", {{{"type", "directional"}, {"direction", light}, {"irradiance", 1.0}}}},
                        {"integrator", {{"type", "pathtrace"}}}};
  return nimbus::parse_scene(doc, "bench", ".");
}

double cpu_seconds() {
  timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

struct Result {
  double mean = 0.0, var_per_sample = 0.0, ns_per_sample = 0.0;
};

Result measure(const nimbus::Scene& scene, int spp, int K, int threads) {
  const size_t n = scene.camera.width * scene.camera.height * 3;
  std::vector<double> sum(n, 0.0), sum2(n, 0.0);
  double seconds = 0.0;
  for (int k = 0; k < K; ++k) {
    nimbus::RenderOptions opt;
    opt.spp = spp;
    opt.threads = threads;
    opt.seed = uint64_t(1000 + k);
    const double t0 = cpu_seconds();
    const nimbus::RenderResult r = nimbus::render(scene, opt);
    seconds += cpu_seconds() - t0;
    for (size_t i = 0; i < n; ++i) {
      sum[i] += r.image.rgb[i];
      sum2[i] += double(r.image.rgb[i]) * r.image.rgb[i];
    }
  }
  Result res;
  for (size_t i = 0; i < n; ++i) {
    const double m = sum[i] / K;
    res.mean += m / n;
    res.var_per_sample += (sum2[i] - K * m * m) / (K - 1) * spp / n;
  }
  res.ns_per_sample = seconds * 1e9 / (double(K) * spp * (n / 3));
  return res;
}

}  // namespace

int main(int argc, char** argv) {
  const int spp = argc > 1 ? std::atoi(argv[1]) : 16;
  const int K = argc > 2 ? std::atoi(argv[2]) : 8;
  const int threads = argc > 3 ? std::atoi(argv[3]) : 1;
  struct Case {
    const char* name;
    nimbus::Scene scene;
  };
  const std::vector<Case> cases = {
      {"sphere_r2_a0.99_hg0.85_front", sphere(2, 0.99, 0.85, {0.2, 1, -0.25})},
      {"sphere_r10_a0.99_hg0.85_side", sphere(10, 0.99, 0.85, {1, 0, 0})},
      {"sphere_r10_a0.99_hg0.85_back", sphere(10, 0.99, 0.85, {0.2, -1, 0.25})},
  };
  std::printf("%-30s %10s %14s %12s %14s\n", "scene", "mean", "var/sample", "ns/sample", "efficiency");
  for (const Case& c : cases) {
    const Result r = measure(c.scene, spp, K, threads);
    std::printf("%-30s %10.5f %14.6e %12.1f %14.4e\n", c.name, r.mean, r.var_per_sample, r.ns_per_sample,
                1e9 / (r.var_per_sample * r.ns_per_sample));
  }
  return 0;
}
