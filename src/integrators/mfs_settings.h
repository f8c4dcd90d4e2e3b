// `mfs`'s "auto" choices, made once per render by MfsIntegrator from the scene (mfs_settings.cpp; the
// settings' JSON is declared in mfs.h).
#pragma once

#include <optional>
#include <vector>

#include "integrators/mfs.h"

namespace nimbus {

// The photons' own majorant grid (exact per-cell maxima) where the grids' voxels are few enough per
// photon (the scatter grid's and the beam grid's, beam_counts per light) for it to pay; else nullopt.
std::optional<MajorantGrid> photon_majorant_grid(const SceneContext& ctx, const MfsSettings& s,
                                                 const std::vector<int>& beam_counts);
// "auto" scatter (and beam) grid nodes along the media's longest axis.
int auto_scatter_grid_resolution(const SceneContext& ctx);
// "auto" scatter-grid bands: 1 where every medium scatters isotropically (no peak, and its phase function's
// moments for l = 1, 2 vanish), else 3.
int auto_scatter_grid_bands(const std::vector<const PhaseSplit*>& splits);
// "auto" scatter-grid photons from the whole image's pixels, halved where the camera looks into a light's
// forward peak (the widest peak's cut angle [rad]).
int auto_photons(const SceneContext& ctx, double cut_angle);
// "auto" beam-grid photons per light, given the widest peak's cut angle [rad] (0: no medium has a peak, and
// every light gets none).
std::vector<int> auto_beam_photons(const SceneContext& ctx, double cut_angle,
                                   std::optional<double> collisions = std::nullopt);
// "auto" edge samples (MfsSettings::edge_samples), given the widest peak's cut angle [rad].
int auto_edge_samples(const SceneContext& ctx, double cut_angle);
// The scatter grid's settings from mfs's (photons resolved; adaptive: they were "auto").
ScatterGridSettings scatter_grid_settings(const MfsSettings& s, bool adaptive, uint64_t seed,
                                          const MajorantGrid* tracking);

}  // namespace nimbus
