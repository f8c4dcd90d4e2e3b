// The shadow maps (integrators/shadow_map.h): reduced extinction, marched transmittance, the node grid.
#include "integrators/shadow_map.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "integrators/tracking.h"
#include "scene/lights.h"

namespace nimbus {

Rgb reduced_sigma_t(const SceneMedia& media, const Vec3& p, const std::vector<double>& peak_fraction) {
  if (peak_fraction.empty()) return media.sigma_t(p);
  MediumPoint mp;
  media.eval(p, &mp);
  Rgb s = mp.sigma_t();
  for (int i = 0; i < mp.count && i < int(peak_fraction.size()); ++i) s -= mp.sigma_s_i[i] * peak_fraction[i];
  return s;
}

Rgb marched_transmittance(const SceneMedia& media, const MajorantGrid& grid, const Vec3& p, const Vec3& w,
                          double tmax, double tau_step, const std::vector<double>& peak_fraction) {
  Rgb tau(0.0);
  march(grid, p, w, tmax, tau_step, 0.5, [&](const Vec3& x, double, double dt) {
    tau += reduced_sigma_t(media, x, peak_fraction) * dt;
    return min_component(tau) < 50.0;
  });
  return exp(-tau);
}

template <typename OneNode>
void TransmittanceGrid::fill(const MajorantGrid& grid, int resolution, TransmittanceGrid* second,
                             OneNode&& one_node) {
  Bounds bounds = grid.bounds();
  if (bounds.empty()) {
    bounds.lo = Vec3(0.0);
    bounds.hi = Vec3(1.0);
  }
  grid_ = node_grid_spanning(bounds, resolution);
  values_.assign(grid_.size() * 3, 0.0f);
  if (second) second->grid_ = grid_, second->values_.assign(grid_.size() * 3, 0.0f);
  // Nodes keep the optical depth -log T: lookups interpolate it and exponentiate (see lookup).
  auto depth = [](double T) { return float(-std::log(std::max(T, 1e-300))); };
  tbb::parallel_for(0, grid_.nodes[2], [&](int z) {
    for (int y = 0; y < grid_.nodes[1]; ++y) {
      for (int x = 0; x < grid_.nodes[0]; ++x) {
        Rgb T(1.0), T2(1.0);
        one_node(grid_.position(x, y, z), &T, second ? &T2 : nullptr);
        const size_t i = grid_.index(x, y, z) * 3;
        for (int c = 0; c < 3; ++c) values_[i + c] = depth(T[c]);
        if (second)
          for (int c = 0; c < 3; ++c) second->values_[i + c] = depth(T2[c]);
      }
    }
  });
}

TransmittanceGrid::TransmittanceGrid(const SceneMedia& media, const MajorantGrid& grid, const Light& light,
                                     int resolution, double tau_step,
                                     const std::vector<double>& peak_fraction) {
  fill(grid, resolution, nullptr, [&](const Vec3& p, Rgb* T, Rgb*) {
    // The centre of the light (a sun disc is treated as its centre direction here; a spot's map
    // covers its whole sphere of directions, the cone is applied by sample_light).
    Vec3 wi;
    double distance = 0.0;
    if (light_centre(light, p, &wi, &distance))
      *T = marched_transmittance(media, grid, p, wi, distance, tau_step, peak_fraction);
  });
}

void TransmittanceGrid::build_pair(const SceneMedia& media, const MajorantGrid& grid, const Light& light,
                                   int resolution, double tau_step, const std::vector<double>& peak_fraction,
                                   TransmittanceGrid* full, TransmittanceGrid* reduced) {
  full->fill(grid, resolution, reduced, [&](const Vec3& p, Rgb* T_full, Rgb* T_reduced) {
    Vec3 wi;
    double distance = 0.0;
    if (!light_centre(light, p, &wi, &distance)) return;
    // Each sum stops after the step that takes it to 50 (as marched_transmittance alone does).
    Rgb tau(0.0), tau_reduced(0.0);
    bool full_done = false;
    MediumPoint mp;
    march(grid, p, wi, distance, tau_step, 0.5, [&](const Vec3& x, double, double dt) {
      media.eval(x, &mp);
      Rgb s = mp.sigma_t();
      if (!full_done) tau += s * dt, full_done = min_component(tau) >= 50.0;
      for (int i = 0; i < mp.count && i < int(peak_fraction.size()); ++i)
        s -= mp.sigma_s_i[i] * peak_fraction[i];
      tau_reduced += s * dt;
      return !full_done || min_component(tau_reduced) < 50.0;
    });
    *T_full = exp(-tau);
    *T_reduced = exp(-tau_reduced);
  });
}

Rgb TransmittanceGrid::lookup(const Vec3& p) const {
  const TrilinearStencil st = grid_.stencil(p);
  // Interpolated in optical depth, not in transmittance: exp is convex, so a lerp of T between a node
  // the light reaches and one deep in shadow is too bright (by up to ~50 % where the light grazes a dense
  // medium's boundary, the backlit spheres' rim; docs/validation/render.md), while the depth along the
  // light's path varies smoothly.
  if (values_.empty()) return Rgb(0.0);
  Rgb tau(0.0);
  for (int k = 0; k < 8; ++k) {
    const float* v = &values_[st.node[k] * 3];
    tau += Rgb(v[0], v[1], v[2]) * st.weight[k];
  }
  return exp(-tau);
}

}  // namespace nimbus
