// Writes a procedural fire as an OpenVDB file with the grids an emitting medium can draw from one file
// (docs/scene-format.md, "emission"): `density` (smoke and soot, voxel h), `color` (vec3 soot tint, voxel
// h), `temperature` (in units of 1000 K, voxel 2h: another voxel size) and `flame` (0 .. 1 where it burns,
// voxel 2h). A rising plume 2 x 2 x 3 world units (z up, base at z = 0), turbulent by the gradient noise of
// the procedural cloud (media/cloud.h). Deterministic.
//
//   make_fire OUT.vdb [voxels across, default 64]
#include <openvdb/openvdb.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "media/cloud.h"

namespace {

using nimbus::Vec3;

double smoothstep(double a, double b, double x) {
  const double t = std::clamp((x - a) / (b - a), 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

// The plume's point after turbulent displacement (growing with height).
Vec3 displaced(const Vec3& p) {
  const double h = std::clamp(p.z / 3.0, 0.0, 1.0);
  const Vec3 q(p.x * 2.0, p.y * 2.0, p.z * 1.3 - 0.0);
  const double a = 0.12 + 0.35 * h;
  return p + Vec3(nimbus::fbm(q, 11, 4), nimbus::fbm(q, 12, 4), 0.5 * nimbus::fbm(q, 13, 4)) * a;
}

// Temperature in units of 1000 K: hot core near the base, cooling with height and radius.
double temperature(const Vec3& p) {
  const Vec3 q = displaced(p);
  const double h = q.z / 3.0;
  if (h <= 0.0 || h >= 1.0) return 0.0;
  const double radius = 0.55 * (1.0 - 0.55 * h);
  const double r = std::hypot(q.x, q.y) / radius;
  const double core = std::exp(-2.5 * r * r) * smoothstep(0.0, 0.06, h) * std::pow(1.0 - h, 1.3);
  return 1.9 * core * (0.8 + 0.2 * nimbus::fbm(q * 3.0, 14, 3));
}

// Smoke and soot: thin in the flame, thick in the plume above it, widening as it rises.
double density(const Vec3& p) {
  const Vec3 q = displaced(p);
  const double h = q.z / 3.0;
  if (h <= 0.0 || h >= 1.0) return 0.0;
  const double radius = 0.35 + 0.5 * h;
  const double r = std::hypot(q.x, q.y) / radius;
  const double body = smoothstep(1.0, 0.6, r) * smoothstep(0.0, 0.15, h) * smoothstep(1.0, 0.8, h);
  const double puffs = std::max(0.0, 0.6 + 0.8 * nimbus::fbm(q * 2.5, 15, 4));
  return body * puffs * (0.15 + 0.85 * smoothstep(0.15, 0.55, h));
}

openvdb::math::Transform::Ptr frame(double h) {
  auto t = openvdb::math::Transform::createLinearTransform(h);
  t->postTranslate(openvdb::Vec3d(-1.0 + 0.5 * h, -1.0 + 0.5 * h, 0.5 * h));
  return t;
}

template <typename GridT, typename F>
typename GridT::Ptr voxelise(const std::string& name, double h, int nx, int nz, F&& f) {
  auto grid = GridT::create();
  grid->setName(name);
  grid->setTransform(frame(h));
  grid->setGridClass(openvdb::GRID_FOG_VOLUME);
  auto acc = grid->getAccessor();
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < nx; ++j)
      for (int i = 0; i < nx; ++i) {
        const Vec3 p(-1.0 + (i + 0.5) * h, -1.0 + (j + 0.5) * h, (k + 0.5) * h);
        f(acc, openvdb::Coord(i, j, k), p);
      }
  grid->pruneGrid();
  return grid;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: make_fire OUT.vdb [voxels across, default 64]\n");
    return 2;
  }
  const int n = argc > 2 ? std::atoi(argv[2]) : 64;
  openvdb::initialize();
  const double h = 2.0 / n;
  const int nz = n * 3 / 2;
  auto d = voxelise<openvdb::FloatGrid>("density", h, n, nz, [](auto& acc, const auto& c, const Vec3& p) {
    const double v = density(p);
    if (v > 1e-3) acc.setValue(c, float(v));
  });
  auto color = voxelise<openvdb::Vec3SGrid>("color", h, n, nz, [](auto& acc, const auto& c, const Vec3& p) {
    if (density(p) <= 1e-3) return;
    const double hot = std::min(1.0, temperature(p) / 1.2);  // soot darkens and browns near the flame
    acc.setValue(c,
                 openvdb::Vec3s(float(0.92 - 0.45 * hot), float(0.9 - 0.55 * hot), float(0.88 - 0.65 * hot)));
  });
  auto T = voxelise<openvdb::FloatGrid>("temperature", 2 * h, n / 2, nz / 2,
                                        [](auto& acc, const auto& c, const Vec3& p) {
                                          const double v = temperature(p);
                                          if (v > 1e-3) acc.setValue(c, float(v));
                                        });
  auto flame = voxelise<openvdb::FloatGrid>("flame", 2 * h, n / 2, nz / 2,
                                            [](auto& acc, const auto& c, const Vec3& p) {
                                              const double v = smoothstep(0.9, 1.5, temperature(p));
                                              if (v > 1e-3) acc.setValue(c, float(v));
                                            });
  openvdb::GridPtrVec grids{d, T, flame, color};
  openvdb::io::File file(argv[1]);
  file.write(grids);
  file.close();
  std::printf("wrote %s: density %zu, temperature %zu, flame %zu, color %zu active voxels\n", argv[1],
              size_t(d->activeVoxelCount()), size_t(T->activeVoxelCount()), size_t(flame->activeVoxelCount()),
              size_t(color->activeVoxelCount()));
  return 0;
}
