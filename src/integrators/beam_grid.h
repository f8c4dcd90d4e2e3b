// The lights' peak-only beams (light that has not yet scattered widely) as they really travel, against
// the straight-line picture `mfs` uses for them: from the light's entry, T_wide = exp(-int (sigma_a +
// (1 - f) sigma_s)) along the straight line (the reduced shadow map), as if every peak scatter kept the
// light on its line. Peak scatters deflect it: its paths are longer (more absorption and wide
// scattering on the way, the corrected kernel's 1 / cosh loss), and near a medium's sides it spreads out
// of the medium and into its shadow. Per light and node:
//     R(x) = phi_peak(x) / (phi_0(x) T_wide(x)),
// phi_peak the fluence of the peak-only light, estimated by photons traced through the true medium:
// flights end at peak scatters only (rate sum_m f_m sigma_s,m; the new direction from P_peak), while
// absorption and wide scatters are a continuous loss exp(-int sigma_loss) on the photon's weight, so in
// a uniform medium a photon's weight depends only on its path length. Track-length deposits are each
// divided by the model phi_0 T_wide at the deposit point (phi_0: the unattenuated fluence, the
// irradiance or I / r^2), and the same photon is deposited once more undeflected (the model itself, with
// the same emission: a control variate), so R = traced / straight is 1 wherever nothing deflects the
// light; a photon's first flight and its straight deposit share their samples up to its first peak
// scatter. Photons enter through a stratified disc or cone (the R2 sequence). With `spread` (beam_spread
// "traced"), the traced deposits also carry 1 - the cosine to the straight direction from the light: the
// beam's spread, 1 - its mean cosine, which then sets the angular spread `mfs` gives the peak-only light
// (by default it keeps the straight beam's spread, which is closer to the path tracer on the suite's
// backlit spheres: docs/benchmarks.md, "The beam's spread"). The straight deposits then carry the straight
// model's spread, 1 - exp(-tau (1 - chi_1)) at its peak depth tau = ln(T_wide / T_light) (eq. D3 at l = 1),
// as its control variate: the spread read at p is the traced spread as tallied, plus the model's at p,
// minus the model's as tallied. Where the spread changes faster than the nodes resolve (the lit side of a
// dense medium, where it grows from 0 at the surface) the model's exact value at p carries the change and
// the nodes only the difference (eq. D9b): a cell-averaged spread made the lit rim of a backlit sphere too
// dark. `mfs` multiplies T_wide by R. Two more columns tally the traced and the straight deposits without
// the division by the model, and R is at most their ratio: where the model's T_wide falls by orders of
// magnitude within a cell (a dense cloud's shadow edges, a smoke's filaments) the mean of traced / model
// is set by the cell's darkest samples, and T_wide R would light its brighter parts beyond what its photons
// carried there (docs/validation/render.md, "A dense cloud"). Deposits in cells with no
// medium in or next to them are skipped (nothing there is read where a medium scatters), so far from
// the media (the grid's padding, the empty space and the shadows within its bounds) R is incomplete.
#pragma once

#include <cstdint>
#include <vector>

#include "core/node_grid.h"
#include "integrators/integrator.h"
#include "integrators/shadow_map.h"
#include "media/majorant.h"
#include "transport/phase_split.h"

namespace nimbus {

// What a beam grid with a camera tallies towards it: the traced beam's P_peak (peak_toward_camera, eq. D15)
// and its P_wide, with the straight model's wide factor at the same samples (wide_toward_camera).
struct BeamCameraTallies {
  bool peak = true;
  bool wide = false;
};

class BeamGrid {
 public:
  // full_maps[l], reduced_maps[l]: light l's T_light and T_wide, a pair of one layout (build_pair; empty
  // maps: the chord in closed form, for one constant-density sphere or box only; the full maps are read
  // only with `spread`); photons: per light (0: none); resolution as ScatterGridSettings. spread: tally the spread
  // (the straight model's takes medium 0's chi_1).
  // skip_idle: no deposits in cells with no medium in them or next to them (the lookup is the same
  // wherever there is a medium; for tests: false deposits everywhere). smoothing: passes of the filter
  // [1 2 1] / 4 along each axis over the nodes inside the media, every column of the tallies alike (the
  // nodes outside untouched; `mfs`'s beam_smoothing).
  BeamGrid(const SceneContext& ctx, const std::vector<const PhaseSplit*>& splits,
           const std::vector<double>& peak_fraction, const std::vector<TransmittanceGrid>& full_maps,
           const std::vector<TransmittanceGrid>& reduced_maps, const std::vector<int>& photons,
           int resolution, uint64_t seed, bool spread, const Vec3* camera = nullptr,
           const MajorantGrid* majorants = nullptr, bool skip_idle = true, int smoothing = 0,
           BeamCameraTallies tallies = {});
  // R for light `light` at p (trilinear between nodes; at most the plain tallies' ratio there) and, if
  // mean_cosine is not null, the peak-only light's mean cosine to the straight direction from the light,
  // given the straight model's T_light and T_wide at p (the spread's control variate; a grid without
  // `spread`: the straight model's); false (nothing written) outside the grid and for other lights.
  // With a camera, peak_toward (if not null) gets the traced beam's P_peak (medium 0's) towards the camera,
  // averaged over its directions: the angular factor of the forward peak alone (eq. D7's peak_eff).
  // With the wide tallies, wide_ratio (if not null) gets the traced beam's P_wide towards the camera over
  // the straight model's wide_eff(ln(T_wide / T_light), mu) at the same samples (1 where either is 0).
  bool lookup(size_t light, const Vec3& p, const Rgb& T_light, const Rgb& T_wide, Rgb* factor,
              Rgb* mean_cosine, Rgb* peak_toward = nullptr, Rgb* wide_ratio = nullptr) const;
  // The same from st, node_grid().stencil(p), found once for grids of the same layout (the scatter grid's).
  bool lookup(size_t light, const Vec3& p, const TrilinearStencil& st, const Rgb& T_light, const Rgb& T_wide,
              Rgb* factor, Rgb* mean_cosine, Rgb* peak_toward = nullptr, Rgb* wide_ratio = nullptr) const;
  const NodeGrid& node_grid() const { return grid_; }
  bool has_camera() const { return with_camera_; }
  bool has_wide() const { return with_wide_; }
  // Floats per column of a node: 1 where grey media and grey lights make the three channels the same
  // numbers (channel 0 is kept and stands for all), else 3.
  int channels() const { return channels_; }
  size_t memory_bytes() const;
  // Peak scatters whose direction the rejection sampler could not draw (the photon flew on
  // undeflected; see sample_by_rejection). 0 in every normal case.
  uint64_t rejection_failures() const { return rejection_failures_; }
  // The share of the grid's cells whose deposits were skipped (no medium in or next to them).
  double idle_share() const { return idle_share_; }

 private:
  NodeGrid grid_;                   // the media's bounds padded by one spacing (node_grid_padded)
  std::vector<FloatArray> values_;  // per light and node: traced, straight (, their spreads) (, P_peak)
  double one_minus_chi1_ = 0.0;     // medium 0's peak: the straight model's spread
  uint64_t rejection_failures_ = 0;
  double idle_share_ = 0.0;
  bool with_camera_;  // the nodes hold a column of P_peak towards camera_
  bool with_wide_;    // the nodes hold columns of P_wide and the model's wide factor towards camera_
  bool spread_;       // the nodes hold the traced and the straight spread
  int channels_ = 3;  // floats per column
  int stride_ = 0;    // floats per node
  Vec3 camera_{0.0};  // the point P_peak is tallied towards
};

// `passes` times, along each axis in turn, the filter [1 2 1] / 4 over the nodes of g inside the media
// (inside[n] != 0), `stride` floats per node, every float alike: a neighbour outside (or beyond the grid) is
// left out and the weights renormalised; the nodes outside keep their values. (BeamGrid's smoothing.)
void smooth_nodes_inside(FloatArray* v, const NodeGrid& g, const std::vector<uint8_t>& inside, int stride,
                         int passes);
// Per node of g: 1 where a medium has a density at the node itself.
std::vector<uint8_t> nodes_inside(const NodeGrid& g, const SceneMedia& media);

}  // namespace nimbus
