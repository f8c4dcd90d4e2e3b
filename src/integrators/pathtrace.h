// The reference: an unbiased volumetric path tracer.
//
// Null-scattering delta tracking against the majorant grid; chromatic media by spectral tracking
// (one scalar majorant for all channels, collision events chosen with channel-averaged
// probabilities weighted by the path throughput and per-channel weights: Kutz et al. 2017's
// history-aware spectral tracking); next-event estimation to every light
// with ratio-tracked transmittance (the environment through a phase-sampled direction); exact
// phase sampling; unbiased Russian roulette.
#pragma once

#include "integrators/integrator.h"

namespace nimbus {

class PathTracer final : public Integrator {
 public:
  PathTracer(const SceneContext& context, int max_events) : ctx_(context), max_events_(max_events) {}
  Rgb sample(double px, double py, Rng& rng) const override;
  // Radiance arriving at o from direction -d (a ray o + t d), for tests and other integrators.
  Rgb radiance(const Vec3& o, const Vec3& d, Rng& rng) const;

 private:
  // Next-event estimate at a scattering vertex p of medium `medium`, the path travelling along d.
  Rgb direct_light(const Vec3& p, const Vec3& d, int medium, Rng& rng) const;

  const SceneContext& ctx_;
  int max_events_ = 0;
};

}  // namespace nimbus
