// The scene's media prepared for rendering: densities, coefficients at a point, conservative
// maxima over boxes (for the majorant grid). Overlapping media add their coefficients.
#pragma once

#include <array>
#include <vector>

#include "core/math.h"
#include "media/emission.h"
#include "nimbus/scene.h"

namespace nimbus {

inline constexpr int kMaxMedia = 16;

// Coefficients at one point: per-medium scattering (to pick the phase function) and totals.
struct MediumPoint {
  int count = 0;
  std::array<Rgb, kMaxMedia> sigma_s_i{};  // scattering of each medium at the point
  Rgb sigma_s{0.0}, sigma_a{0.0};          // totals
  Rgb emission{0.0};                       // emitted radiance per unit length, all media (media/emission.h)
  Rgb sigma_t() const { return sigma_s + sigma_a; }
};

class SceneMedia {
 public:
  explicit SceneMedia(const std::vector<Medium>& media);

  int count() const { return int(media_.size()); }
  const Medium& medium(int i) const { return media_[i]; }
  const Phase& phase(int i) const { return media_[i].phase; }
  // World-space bounds of the union of all media (empty when there are none).
  const Bounds& bounds() const { return bounds_; }
  const Bounds& bounds(int i) const { return medium_bounds_[i]; }

  // Shape density of medium i at world point p (1 inside analytic shapes, the grid value for grids),
  // looked up at the point the medium's transform takes to p (media without one skip the mapping).
  double density(int i, const Vec3& p) const;
  // A value >= density(i, p) for every p in the world box.
  // exact: for grids, from the voxels rather than the brick maxima (tighter, slower; see
  // DensityGrid::max_density_index_exact).
  double max_density(int i, const Bounds& box, bool exact = false) const;
  void eval(const Vec3& p, MediumPoint* out) const;
  // Whether any medium has density > 0 at p.
  bool inside(const Vec3& p) const;
  // Total extinction per channel at p.
  Rgb sigma_t(const Vec3& p) const;
  // Emission (media/emission.h): whether any medium emits, whether medium i may emit anywhere in the world
  // box (conservative), and the emitted radiance per unit length of all media at p.
  bool emits() const { return emits_; }
  bool may_emit(int i, const Bounds& box) const;
  Rgb emission(const Vec3& p) const;

 private:
  std::vector<Medium> media_;
  std::vector<Bounds> medium_bounds_;
  std::vector<Transform> to_local_;  // world -> the shape's space (the inverse of each medium's transform)
  Bounds bounds_;
  std::vector<MediumEmissionField> fields_;  // emission and colour tint per medium
  bool emits_ = false, tints_ = false;
  // Medium i's grid-world point (media/emission.h) at world point p.
  Vec3 grid_world(int i, const Vec3& p) const;
};

}  // namespace nimbus
