// A deep shadow map: per light, a grid of transmittance towards the light over the media's bounds,
// built once by a deterministic midpoint march in optical-depth steps and read back with trilinear
// interpolation (PVR's cached-transmittance occluder). For directional and point lights.
#pragma once

#include <vector>

#include "core/math.h"
#include "media/majorant.h"
#include "media/media.h"
#include "nimbus/scene.h"

namespace nimbus {

// Transmittance from p along w over [0, tmax] by a midpoint march with steps of at most tau_step
// optical depth against the majorant (deterministic; error O(step^2) for smooth media).
Rgb marched_transmittance(const SceneMedia& media, const MajorantGrid& grid, const Vec3& p, const Vec3& w,
                          double tmax, double tau_step);

class TransmittanceGrid {
 public:
  // resolution: nodes along the longest axis of the media's bounds.
  TransmittanceGrid(const SceneMedia& media, const MajorantGrid& grid, const Light& light, int resolution,
                    double tau_step);
  Rgb lookup(const Vec3& p) const;
  size_t memory_bytes() const { return values_.size() * sizeof(float); }

 private:
  Bounds bounds_;
  std::array<int, 3> nodes_{2, 2, 2};
  Vec3 spacing_{1.0};
  std::vector<float> values_;  // rgb per node
};

}  // namespace nimbus
