// A deep shadow map: per light, a grid of transmittance towards the light over the media's bounds,
// built once by a deterministic midpoint march in optical-depth steps and read back with trilinear
// interpolation (PVR's cached-transmittance occluder). For directional, point and spot lights (towards
// light_centre); area lights are marched to a sampled point instead (integrators/area_light_view.h).
#pragma once

#include <vector>

#include "core/math.h"
#include "core/node_grid.h"
#include "media/majorant.h"
#include "media/media.h"
#include "nimbus/scene.h"

namespace nimbus {

// Extinction at p with a fraction of each medium's scattering removed: sigma_t - sum_i
// peak_fraction[i] sigma_s_i (the forward peak of medium i's
// phase function is not extinction for forward-scattered light; `mfs`). Empty: plain sigma_t.
Rgb reduced_sigma_t(const SceneMedia& media, const Vec3& p, const std::vector<double>& peak_fraction);

// Transmittance from p along w over [0, tmax] by a midpoint march with steps of at most tau_step
// optical depth against the majorant (deterministic; error O(step^2) for smooth media). With
// peak_fraction the extinction is reduced_sigma_t.
Rgb marched_transmittance(const SceneMedia& media, const MajorantGrid& grid, const Vec3& p, const Vec3& w,
                          double tmax, double tau_step, const std::vector<double>& peak_fraction = {});

class TransmittanceGrid {
 public:
  // resolution: nodes along the longest axis of the media's bounds.
  // peak_fraction: see reduced_sigma_t (empty: plain extinction).
  TransmittanceGrid(const SceneMedia& media, const MajorantGrid& grid, const Light& light, int resolution,
                    double tau_step, const std::vector<double>& peak_fraction = {});
  TransmittanceGrid() = default;  // empty (every lookup 0) until build_pair fills it
  // A light's map of the plain extinction and its map of the reduced one (peak_fraction) from one march
  // per node: the march's steps depend on the majorant grid only, so both see the same points and each
  // equals the map built alone (one density lookup per step instead of two).
  static void build_pair(const SceneMedia& media, const MajorantGrid& grid, const Light& light,
                         int resolution, double tau_step, const std::vector<double>& peak_fraction,
                         TransmittanceGrid* full, TransmittanceGrid* reduced);
  Rgb lookup(const Vec3& p) const;
  size_t memory_bytes() const { return values_.size() * sizeof(float); }

 private:
  // The node grid on the media's bounds; fills every node with one_node(position, T, T2) (T2 may be
  // null) into values_ (and second->values_ when given).
  template <typename OneNode>
  void fill(const MajorantGrid& grid, int resolution, TransmittanceGrid* second, OneNode&& one_node);

  NodeGrid grid_;              // nodes on the media's bounds (node_grid_spanning)
  std::vector<float> values_;  // optical depth -log T per node, rgb
};

}  // namespace nimbus
