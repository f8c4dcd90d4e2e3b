// The scatter grid's denoising (integrators/grid_denoise.h).
#include "integrators/grid_denoise.h"

#include <tbb/parallel_for.h>

#include <algorithm>

namespace nimbus {

namespace {

// The mean of a over each node's 3 x 3 x 3 neighbourhood (those within the grid).
std::vector<double> box_mean(const std::vector<double>& a, const NodeGrid& g) {
  std::vector<double> out(a.size(), 0.0);
  tbb::parallel_for(0, g.nodes[2], [&](int z) {
    for (int y = 0; y < g.nodes[1]; ++y)
      for (int x = 0; x < g.nodes[0]; ++x) {
        double sum = 0.0;
        int count = 0;
        for (int k = std::max(0, z - 1); k <= std::min(g.nodes[2] - 1, z + 1); ++k)
          for (int j = std::max(0, y - 1); j <= std::min(g.nodes[1] - 1, y + 1); ++j)
            for (int i = std::max(0, x - 1); i <= std::min(g.nodes[0] - 1, x + 1); ++i, ++count)
              sum += a[g.index(i, j, k)];
        out[g.index(x, y, z)] = sum / count;
      }
  });
  return out;
}

// One pass along axis a of the filter (-3, 12, 17, 12, -3) / 35 from `before` into v, at the nodes whose
// four neighbours along the axis are inside too (the others keep their values). `stride` floats per node.
void filter_axis(FloatArray* v, const FloatArray& before, const NodeGrid& g,
                 const std::vector<uint8_t>& inside, size_t stride, int a) {
  const size_t ns = a == 0 ? 1 : a == 1 ? size_t(g.nodes[0]) : size_t(g.nodes[0]) * g.nodes[1];
  const size_t step = ns * stride;
  tbb::parallel_for(0, g.nodes[2], [&](int z) {
    for (int y = 0; y < g.nodes[1]; ++y)
      for (int x = 0; x < g.nodes[0]; ++x) {
        const size_t n = g.index(x, y, z);
        const int q = a == 0 ? x : a == 1 ? y : z;
        if (!inside[n] || q < 2 || q + 2 >= g.nodes[a] || !inside[n - ns] || !inside[n + ns] ||
            !inside[n - 2 * ns] || !inside[n + 2 * ns])
          continue;
        for (size_t i = n * stride; i < (n + 1) * stride; ++i)
          (*v)[i] = (-3.0f * (before[i - 2 * step] + before[i + 2 * step]) +
                     12.0f * (before[i - step] + before[i + step]) + 17.0f * before[i]) *
                    (1.0f / 35.0f);
      }
  });
}

// kDenoisePasses of filter_axis along each axis in turn.
void smooth_quadratic(FloatArray* v, const NodeGrid& g, const std::vector<uint8_t>& inside, size_t stride) {
  FloatArray before(v->size());
  for (int pass = 0; pass < kDenoisePasses; ++pass)
    for (int a = 0; a < 3; ++a) {
      std::copy(v->begin(), v->end(), before.begin());
      filter_axis(v, before, g, inside, stride, a);
    }
}

}  // namespace

void denoise_grid(FloatArray* values, const NodeGrid& grid, int floats, const FloatArray& per_batch,
                  int batches, const std::vector<int>& probes, const std::vector<uint8_t>& inside) {
  const size_t nodes = grid.size(), P = probes.size(), B = size_t(batches);
  if (nodes == 0 || P == 0 || batches < 2 || per_batch.size() != nodes * B * P || inside.size() != nodes)
    return;
  FloatArray smooth = *values, smooth_batch = per_batch;
  smooth_quadratic(&smooth, grid, inside, size_t(floats));
  smooth_quadratic(&smooth_batch, grid, inside, B * P);
  // Per node: d^2 and the variance of d over the probes together.
  std::vector<double> d2(nodes, 0.0), var(nodes, 0.0);
  for (size_t n = 0; n < nodes; ++n)
    for (size_t p = 0; p < P; ++p) {
      const size_t i = n * size_t(floats) + size_t(probes[p]);
      const double d = double((*values)[i]) - double(smooth[i]), mean = d / double(B);
      double ss = 0.0;
      for (size_t b = 0; b < B; ++b) {
        const size_t j = (n * B + b) * P + p;
        const double db = double(per_batch[j]) - double(smooth_batch[j]) - mean;
        ss += db * db;
      }
      d2[n] += d * d;
      var[n] += ss * double(B) / double(B - 1);
    }
  const std::vector<double> d2_mean = box_mean(d2, grid), var_mean = box_mean(var, grid);
  for (size_t n = 0; n < nodes; ++n) {
    const double D = std::max(0.0, d2_mean[n] - var_mean[n]), V = var_mean[n];
    const double keep = D + V > 0.0 ? D / (D + V) : 1.0;
    float* v = &(*values)[n * size_t(floats)];
    const float* s = &smooth[n * size_t(floats)];
    for (int h = 0; h < floats; ++h) v[h] = float(s[h] + keep * (v[h] - s[h]));
  }
}

}  // namespace nimbus
