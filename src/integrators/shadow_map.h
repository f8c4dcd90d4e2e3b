// A deep shadow map: per light, a grid of transmittance towards the light over the media's bounds,
// built once by deterministic midpoint marches in optical-depth steps, kept as optical depth per node and
// read back by trilinear interpolation of the depth (PVR's cached-transmittance occluder; the depth, not
// T, because a lerp of T errs by the convexity of exp). For directional, point and spot lights (towards
// light_centre); area lights are marched to a sampled point instead (integrators/area_light_view.h).
// A directional light's map is swept slice by slice towards the light (MapBuild); the others march
// from every node to the light.
#pragma once

#include <vector>

#include "core/math.h"
#include "core/node_grid.h"
#include "core/zeroed_floats.h"
#include "media/majorant.h"
#include "media/media.h"
#include "nimbus/scene.h"

namespace nimbus {

// Extinction at p with a fraction of each medium's scattering removed: sigma_t - sum_i
// peak_fraction[i] sigma_s_i (the forward peak of medium i's
// phase function is not extinction for forward-scattered light; `mfs`). Empty: plain sigma_t.
Rgb reduced_sigma_t(const SceneMedia& media, const Vec3& p, const std::vector<double>& peak_fraction);
// The same from the media's values at the point (SceneMedia::eval), for a non-empty peak_fraction: the same
// arithmetic, so the same bits.
Rgb reduced_sigma_t(const MediumPoint& mp, const std::vector<double>& peak_fraction);

// Transmittance from p along w over [0, tmax] by a midpoint march with steps of at most tau_step
// optical depth against the majorant (deterministic; error O(step^2) for smooth media). With
// peak_fraction the extinction is reduced_sigma_t.
Rgb marched_transmittance(const SceneMedia& media, const MajorantGrid& grid, const Vec3& p, const Vec3& w,
                          double tmax, double tau_step, const std::vector<double>& peak_fraction = {});

// How a map is built. march: every node marches to the light, O(N) lookups per node (the reference).
// sweep (directional lights; the others march): the node slices across the axis most aligned with
// the light (per node spacing) are visited from the one nearest the light, and a node takes the
// optical depth `stride` slices nearer the light, interpolated in that slice (0 outside the media's
// bounds), plus its own march over that short segment: O(stride) lookups per node. The
// interpolation blurs the map across the light's direction by about sqrt(slices / stride) x 0.5 node
// spacings at worst (tests/integrators/shadow_map_test.cpp measures it against the march).
struct MapBuild {
  bool sweep = true;
  int stride = 2;     // slices per sweep step, >= 1
  bool cubic = true;  // Catmull-Rom interpolation in the slice (kept within the middle nodes), else bilinear
};

class TransmittanceGrid {
 public:
  // resolution: nodes along the longest axis of the media's bounds.
  // peak_fraction: see reduced_sigma_t (empty: plain extinction).
  TransmittanceGrid(const SceneMedia& media, const MajorantGrid& grid, const Light& light, int resolution,
                    double tau_step, const std::vector<double>& peak_fraction = {}, MapBuild how = {});
  TransmittanceGrid() = default;  // empty (every lookup 0) until build_pair fills it
  // A light's map of the plain extinction and its map of the reduced one (peak_fraction) from one walk:
  // the marches' steps depend on the majorant grid only, so both see the same points and each equals
  // the map built alone (one density lookup per step instead of two).
  static void build_pair(const SceneMedia& media, const MajorantGrid& grid, const Light& light,
                         int resolution, double tau_step, const std::vector<double>& peak_fraction,
                         TransmittanceGrid* full, TransmittanceGrid* reduced, MapBuild how = {});
  Rgb lookup(const Vec3& p) const;
  // The same from the trilinear stencil at p: the pair of build_pair shares its node layout, so one
  // stencil (either map's) serves both (bit for bit as lookup(p)).
  TrilinearStencil stencil(const Vec3& p) const { return grid_.stencil(p); }
  Rgb lookup(const TrilinearStencil& st) const;
  size_t memory_bytes() const { return values_.size() * sizeof(float); }

 private:
  // Builds the full map (plain extinction) into `full` and the reduced one into `reduced` (either may be
  // null) on the node grid of the media's bounds.
  static void build(const SceneMedia& media, const MajorantGrid& grid, const Light& light, int resolution,
                    double tau_step, const std::vector<double>& peak_fraction, TransmittanceGrid* full,
                    TransmittanceGrid* reduced, MapBuild how);

  NodeGrid grid_;      // nodes on the media's bounds (node_grid_spanning)
  FloatArray values_;  // optical depth -log T per node, rgb
};

}  // namespace nimbus
