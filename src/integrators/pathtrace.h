// The reference: an unbiased volumetric path tracer.
//
// Null-scattering delta tracking against the majorant grid; chromatic media by spectral tracking
// (one scalar majorant for all channels, collision events chosen with channel-averaged
// probabilities weighted by the path throughput and per-channel weights: Kutz et al. 2017's
// history-aware spectral tracking); next-event estimation to every light
// with ratio-tracked transmittance (the environment through a phase-sampled direction); exact
// phase sampling; unbiased Russian roulette.
#pragma once

#include <memory>
#include <vector>

#include "integrators/integrator.h"
#include "transport/phase_split.h"

namespace nimbus {

// Optional: the radiance of the paths with at most `max_wide_scatters` wide scatters, for the
// validation of `mfs` order by order. Each phase function is split as `mfs` splits it,
// P = f P_peak + (1 - f) P_wide; a sampled scatter into cosine mu counts as wide with probability
// (1 - f) P_wide(mu) / P(mu), a next-event connection contributes its wide and peak parts to the
// right counts. Unbiased for that partition of the radiance; off (the full radiance) by default.
struct PathTraceSettings {
  int max_wide_scatters = -1;   // < 0: off
  double peak_fraction = -1.0;  // < 0: auto (g^2), as mfs
};

PathTraceSettings parse_pathtrace_settings(const nlohmann::json& options, const std::string& where, bool strict);

class PathTracer final : public Integrator {
 public:
  PathTracer(const SceneContext& context, int max_events, PathTraceSettings settings = {});
  Rgb sample(double px, double py, Rng& rng) const override;
  // Radiance arriving at o from direction -d (a ray o + t d), for tests and other integrators.
  Rgb radiance(const Vec3& o, const Vec3& d, Rng& rng) const;

 private:
  // Next-event estimate at a scattering vertex p of medium `medium`, the path travelling along d.
  // wide_scatters: wide scatters on the path so far (only used with a wide-scatter limit).
  Rgb direct_light(const Vec3& p, const Vec3& d, int medium, int wide_scatters, Rng& rng) const;
  // The weight of a scatter into cosine mu in medium i for a path with `wide` wide scatters before it.
  double split_weight(int medium, double mu, int wide) const;

  const SceneContext& ctx_;
  int max_events_ = 0;
  PathTraceSettings s_;
  std::vector<std::unique_ptr<PhaseSplit>> splits_;
};

}  // namespace nimbus
