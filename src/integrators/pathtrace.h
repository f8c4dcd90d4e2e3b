// The reference: an unbiased volumetric path tracer.
//
// Null-scattering delta tracking against the majorant grid; chromatic media by spectral tracking
// (one scalar majorant for all channels, collision events chosen with channel-averaged
// probabilities weighted by the path throughput and per-channel weights: Kutz et al. 2017's
// history-aware spectral tracking); next-event estimation to every light with ratio-tracked
// transmittance (a constant environment through a phase-sampled direction, an environment image by
// MIS of a map- and a phase-sampled direction: integrators/env_light.h); exact phase sampling;
// unbiased Russian roulette. Where every medium is a constant-density sphere or box (no emission),
// free flights are tracked against their exact extinction, piece by piece (grey media: no null
// collisions), and the transmittance is taken in closed form (media/analytic_media.h).
//
// Options (the JSON fields of the scene's integrator block besides type, spp, seed, max_events):
//
// | field               | type                    | default | meaning                                        |
// |---------------------|-------------------------|---------|------------------------------------------------|
// | `max_wide_scatters` | integer >= 0 (or absent) | absent  | count only paths with at most K wide scatters (mfs's partition, for validating mfs order by order); absent: the full radiance |
// | `peak_fraction`     | "auto" or [0, 0.99]     | "auto"  | f of the wide/peak split with max_wide_scatters ("auto": g^2 per medium, as mfs) |
#pragma once

#include <memory>
#include <optional>
#include <vector>

#include "integrators/integrator.h"
#include "integrators/path_clock.h"
#include "transport/phase_split.h"

namespace nimbus {

// Optional: the radiance of the paths with at most `max_wide_scatters` wide scatters, for the
// validation of `mfs` order by order. Each phase function is split as `mfs` splits it,
// P = f P_peak + (1 - f) P_wide; a sampled scatter into cosine mu counts as wide with probability
// (1 - f) P_wide(mu) / P(mu), a next-event connection contributes its wide and peak parts to the
// right counts. Unbiased for that partition of the radiance; off (the full radiance) by default.
struct PathTraceSettings {
  std::optional<int> max_wide_scatters;  // nullopt: off (the full radiance)
  std::optional<double> peak_fraction;   // nullopt: "auto" (g^2 per medium), as mfs
};

// The integrator block's own fields (strict: unknown keys are errors naming `where` and the JSON path),
// and back.
PathTraceSettings pathtrace_settings_from_json(const nlohmann::json& options, const std::string& where);
nlohmann::json to_json(const PathTraceSettings& s);

class PathTracer final : public Integrator {
 public:
  PathTracer(const SceneContext& context, int max_events, PathTraceSettings settings = {});
  Rgb Li(const Ray& ray, Rng& rng, CameraSample* sample = nullptr) const override;
  nlohmann::json settings_json() const override { return to_json(s_); }

 private:
  // Next-event estimate at a scattering vertex p of medium `medium`, the path travelling along d.
  // wide_scatters: wide scatters on the path so far (only used with a wide-scatter limit).
  // Returns it times the path throughput beta. A transient render's clock records each light's part with
  // its connection's length.
  Rgb direct_light(const Vec3& p, const Vec3& d, int medium, int wide_scatters, Rng& rng, const Rgb& beta,
                   const PathClock& clock) const;
  // Samples the continuation after a scatter in `medium`: d becomes the new direction. False when the
  // path ends (over the wide-scatter limit).
  bool scatter(int medium, Vec3& d, int& wide, Rng& rng) const;
  // The path meets surface hit: adds its direct light to L and its albedo to beta. False when the path
  // ends there (a holdout, over the wide-scatter limit, or black).
  bool reflect(const SurfaceHit& hit, Rgb& L, Rgb& beta, int& wide, Rng& rng, const PathClock& clock) const;
  // One collision of delta tracking with the media at a point (mp) under majorant maj, by history-aware
  // spectral tracking: updates the throughput beta. Returns false for a null collision (tracking goes
  // on), true when the flight ends here: a real scatter in medium *scatter_medium, or the path absorbed
  // (beta = 0, *scatter_medium untouched).
  bool collide(const MediumPoint& mp, double maj, Rgb& beta, Rng& rng, int* scatter_medium) const;
  // The weight of a scatter into cosine mu in medium i for a path with `wide` wide scatters before it.
  double split_weight(int medium, double mu, int wide) const;

  const SceneContext& ctx_;
  int max_events_ = 0;
  PathTraceSettings s_;
  std::vector<std::unique_ptr<PhaseSplit>> splits_;
  DistantReference clock_reference_;  // a transient render's plane for distant lights
};

}  // namespace nimbus
