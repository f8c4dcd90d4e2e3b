// Emission in media and the further grids a medium may draw from its volume file (docs/scene-format.md,
// "Emission"): the emitted radiance per unit length j(x) (RGB) of one medium, and the colour grid's tint
// of its scattering. Points are in the medium's grid-world space (a vdb shape's file space: the medium's
// own transform, translate and scale undone), so every grid of the file is sampled in the same frame,
// whatever its voxel size. Analytic and cloud shapes take a constant emission only (no grids).
//
//   j(x) = radiance * (emission_grid(x), or else the shape's density d(x))
//        + intensity * sigma_a * d(x) * blackbody_rgb(temperature_scale * temperature_grid(x) + offset)
#pragma once

#include <array>
#include <memory>

#include "core/math.h"
#include "media/density_grid.h"
#include "nimbus/scene.h"

namespace nimbus {

// The grids besides the density that a medium's emission block names (null: not named).
struct EmissionGrids {
  std::shared_ptr<const DensityGrid> emission, temperature;
  std::array<std::shared_ptr<const DensityGrid>, 3> color;  // a vec3 grid's components (r, g, b)
};

class MediumEmissionField {
 public:
  explicit MediumEmissionField(const Medium& m);
  bool emits() const { return emits_; }
  bool tints() const { return tints_; }
  // j at grid-world point gw where the shape's density is `density`.
  Rgb emission(const Vec3& gw, double density) const;
  // The factor of sigma_s per channel: the colour grid at gw clamped to [0, 1] (1 without one).
  Rgb tint(const Vec3& gw) const;
  // False only where j is 0 everywhere in the grid-world box, given the shape's density there is at most
  // max_density (conservative: for majorants and the emission sampler).
  bool may_emit(const Bounds& gw_box, double max_density) const;
  // Grid-world bounds of the emission, temperature and colour grids (empty without any).
  Bounds grid_bounds() const;

 private:
  MediumEmission e_;
  Rgb sigma_a_{0.0};
  bool emits_ = false, tints_ = false;
};

// The integral of T(t) j over one march step of length dt with j constant and T falling exponentially
// from T0 to T1 (per channel): j dt (T0 - T1) / ln(T0 / T1), exact for a homogeneous step (j dt T0 when
// the step does not attenuate).
Rgb emission_over_step(const Rgb& j, const Rgb& T0, const Rgb& T1, double dt);

}  // namespace nimbus
