#include "media/cloud.h"

#include <array>

#include "core/rng.h"

namespace nimbus {

namespace {

double fade(double t) { return t * t * t * (t * (t * 6.0 - 15.0) + 10.0); }

// Gradient at a lattice point: one of 12 cube-edge directions, chosen by a hash of the point.
double lattice_dot(int ix, int iy, int iz, uint32_t seed, double dx, double dy, double dz) {
  const uint64_t h = mix64((uint64_t(uint32_t(ix)) * 73856093u) ^ (uint64_t(uint32_t(iy)) * 19349663u << 20) ^
                           (uint64_t(uint32_t(iz)) * 83492791u << 40) ^ (uint64_t(seed) << 32));
  static constexpr std::array<std::array<int, 3>, 12> g = {{{1, 1, 0},
                                                            {-1, 1, 0},
                                                            {1, -1, 0},
                                                            {-1, -1, 0},
                                                            {1, 0, 1},
                                                            {-1, 0, 1},
                                                            {1, 0, -1},
                                                            {-1, 0, -1},
                                                            {0, 1, 1},
                                                            {0, -1, 1},
                                                            {0, 1, -1},
                                                            {0, -1, -1}}};
  const auto& v = g[h % 12];
  return v[0] * dx + v[1] * dy + v[2] * dz;
}

struct Blob {
  Vec3 center;
  double radius;
};

// Blobs of a cumulus: a flat-bottomed heap, larger in the middle, towers on top.
std::array<Blob, 14> make_blobs(uint32_t seed) {
  Rng rng(seed, 0x636c6f7564ull);
  std::array<Blob, 14> blobs;
  for (size_t i = 0; i < blobs.size(); ++i) {
    const double a = 2.0 * kPi * rng.uniform(), r = 0.5 * std::sqrt(rng.uniform());
    const double radius = 0.3 + 0.25 * rng.uniform() * (1.0 - r);
    const double z = -0.3 + radius * 0.75 + 0.3 * (0.5 - r) * rng.uniform();
    blobs[i] = {Vec3(r * std::cos(a), r * std::sin(a) * 0.7, z), radius};
  }
  return blobs;
}

}  // namespace

double gradient_noise(const Vec3& p, uint32_t seed) {
  const double fx = std::floor(p.x), fy = std::floor(p.y), fz = std::floor(p.z);
  const int ix = int(fx), iy = int(fy), iz = int(fz);
  const double dx = p.x - fx, dy = p.y - fy, dz = p.z - fz;
  const double u = fade(dx), v = fade(dy), w = fade(dz);
  auto lerp = [](double t, double a, double b) { return a + t * (b - a); };
  const double n000 = lattice_dot(ix, iy, iz, seed, dx, dy, dz);
  const double n100 = lattice_dot(ix + 1, iy, iz, seed, dx - 1, dy, dz);
  const double n010 = lattice_dot(ix, iy + 1, iz, seed, dx, dy - 1, dz);
  const double n110 = lattice_dot(ix + 1, iy + 1, iz, seed, dx - 1, dy - 1, dz);
  const double n001 = lattice_dot(ix, iy, iz + 1, seed, dx, dy, dz - 1);
  const double n101 = lattice_dot(ix + 1, iy, iz + 1, seed, dx - 1, dy, dz - 1);
  const double n011 = lattice_dot(ix, iy + 1, iz + 1, seed, dx, dy - 1, dz - 1);
  const double n111 = lattice_dot(ix + 1, iy + 1, iz + 1, seed, dx - 1, dy - 1, dz - 1);
  return lerp(w, lerp(v, lerp(u, n000, n100), lerp(u, n010, n110)),
              lerp(v, lerp(u, n001, n101), lerp(u, n011, n111)));
}

double fbm(const Vec3& p, uint32_t seed, int octaves) {
  double sum = 0.0, amplitude = 0.5, frequency = 1.0;
  for (int o = 0; o < octaves; ++o) {
    sum += amplitude * gradient_noise(p * frequency, seed + uint32_t(o) * 101u);
    amplitude *= 0.5;
    frequency *= 2.03;
  }
  return sum;
}

double procedural_cloud_density(const Vec3& p, uint32_t seed) {
  static thread_local uint32_t cached_seed = ~0u;
  static thread_local std::array<Blob, 14> blobs;
  if (cached_seed != seed) {
    blobs = make_blobs(seed);
    cached_seed = seed;
  }
  // Smooth union of the blobs as a signed "inside-ness" in units of the radius.
  double field = -1.0;
  for (const Blob& b : blobs) field = std::max(field, 1.0 - length(p - b.center) / b.radius);
  // Billows: displace by fractal noise, stronger towards the top; a flat, sharper base.
  const double billow = fbm(p * 3.5, seed, 5);
  field += 0.45 * billow * (0.6 + 0.4 * std::clamp(p.z + 0.5, 0.0, 1.0)) - 0.05;
  const double base = std::clamp((p.z + 0.32) / 0.08, 0.0, 1.0);
  const double d = std::clamp(field * 6.0, 0.0, 1.0) * base;
  // Keep everything inside the unit ball so the voxelised bounds hold the whole cloud.
  return length(p) < 0.98 ? d : 0.0;
}

}  // namespace nimbus
