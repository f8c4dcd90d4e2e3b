// Filling a CameraSample (integrators/integrator.h) for the media: the free functions and the small
// recorder that the integrators call near the top and the end of Li, so that the layers stay out of
// the estimators. Definitions (docs/compositing.md):
//   depth   where the mean over channels of the camera ray's transmittance crosses 1/2, interpolated
//           within a march step as per-channel exponentials (exact in a homogeneous step);
//   albedo  sigma_s / sigma_t at the march point of the step that holds the depth (0 without one);
//   deep    one segment per march step: the radiance it adds (premultiplied, as seen from the camera)
//           and the mean transmittance it removes, mean(T0) - mean(T1).
#pragma once

#include <vector>

#include "integrators/integrator.h"
#include "media/majorant.h"
#include "media/media.h"
#include "scene/context.h"

namespace nimbus {

// The fraction u in [0, 1] of a step at which mean_c T0_c (T1_c / T0_c)^u = 1/2, for a step that starts
// at or above one half and ends below it (bisection on the monotone per-channel exponentials).
double half_transmittance_fraction(const Rgb& T0, const Rgb& T1);

// The single-scattering albedo sigma_s / sigma_t per channel (0 where sigma_t is 0).
Rgb scattering_albedo(const MediumPoint& mp);

// Depth and albedo of the camera ray o + t d by a deterministic march (midpoint rule, `tau_step` of
// optical depth against the majorant) that stops where the mean transmittance crosses 1/2: for
// integrators that do not march the camera ray themselves (pathtrace).
// Only t < tmax is marched (the first surface); without a crossing the sample is left as it was.
void march_depth(const SceneMedia& media, const MajorantGrid& grid, const Vec3& o, const Vec3& d,
                 double tau_step, CameraSample* sample,
                 double tmax = std::numeric_limits<double>::infinity());

// Records the march of the camera ray (single, octave, mfs) into a CameraSample; with a null sample
// every call is a no-op. step(): one march step from t0 to t0 + dt over which the transmittance the
// background is seen through falls from T0 to T1, mp the coefficients at its march point, L_step the
// radiance the step adds to Li. finish(): the camera ray's direction d, the transmittance the background
// is seen through and the light scattered once (direct = that plus the background).
class MarchRecorder {
 public:
  explicit MarchRecorder(CameraSample* sample) : s_(sample) {}

  void step(double t0, double dt, const Rgb& T0, const Rgb& T1, const MediumPoint& mp, const Rgb& L_step) {
    if (!s_) return;
    const double m0 = average(T0), m1 = average(T1);
    if (m0 >= 0.5 && m1 < 0.5 && !std::isfinite(s_->depth)) {
      s_->depth = t0 + dt * half_transmittance_fraction(T0, T1);
      s_->albedo = scattering_albedo(mp);
    }
    if (s_->deep && (m0 != m1 || max_component(L_step) > 0.0))
      s_->deep->push_back({t0, t0 + dt, L_step, m0 - m1});
  }
  void finish(const SceneContext& ctx, const Vec3& d, const Rgb& T_escape, const Rgb& direct_scattered) {
    if (!s_) return;
    s_->escape_transmittance = T_escape;
    s_->background = ctx.has_environment ? T_escape * ctx.environment_radiance(d) : Rgb(0.0);
    s_->direct = direct_scattered + s_->background;
  }
  bool active() const { return s_ != nullptr; }

 private:
  CameraSample* s_;
};

}  // namespace nimbus
