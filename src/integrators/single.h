// `single`: unscattered plus single-scattered light by a jittered ray march (seed eq. 1).
//
// Steps are fixed in optical depth (tau_step against the majorant of each majorant-grid cell), with
// one random offset per camera ray. Transmittance from each scattering point to the lights is exact
// ratio tracking. Its mean matches `pathtrace` with max_events = 1 up to the step error of the
// camera-side transmittance.
#pragma once

#include "integrators/integrator.h"
#include "integrators/shadow_map.h"
#include "render/lights.h"

namespace nimbus {

struct SingleSettings {
  double tau_step = 0.1;  // optical depth per march step (against the majorant)
  int light_samples = 1;  // ratio-tracking estimates per light per step
  // Transmittance to directional and point lights: exact ratio tracking, or a deep shadow map
  // (deterministic, biased by its resolution). The environment always uses ratio tracking.
  bool shadow_map = false;
  int shadow_map_resolution = 128;  // nodes along the longest axis of the media's bounds
};

// Reads the integrator block's `single` options. strict: unknown keys are errors (the scene names
// this integrator); otherwise other integrators' keys are ignored (--integrator override).
SingleSettings parse_single_settings(const nlohmann::json& options, const std::string& where, bool strict);

class SingleScatter final : public Integrator {
 public:
  SingleScatter(const SceneContext& context, SingleSettings settings);
  Rgb sample(double px, double py, Rng& rng) const override;
  Rgb radiance(const Vec3& o, const Vec3& d, Rng& rng) const;

 private:
  // Transmittance from p towards light l (index into ctx_.lights) along the sampled direction.
  Rgb light_transmittance(size_t l, const Vec3& p, const LightSample& ls, Rng& rng) const;

  const SceneContext& ctx_;
  SingleSettings s_;
  std::vector<TransmittanceGrid> shadow_maps_;  // one per light of ctx_.lights when enabled
};

}  // namespace nimbus
