// `single`: unscattered plus single-scattered light by a jittered ray march (seed eq. 1).
//
// Steps are fixed in optical depth (tau_step against the majorant of each majorant-grid cell), with
// one random offset per camera ray. Transmittance from each scattering point to the lights is exact
// ratio tracking. Its mean matches `pathtrace` with max_events = 1 up to the step error of the
// camera-side transmittance.
//
// Options (the JSON fields of the scene's integrator block besides type, spp, seed, max_events):
//
// | field                   | type                      | default | meaning                                   |
// |-------------------------|---------------------------|---------|-------------------------------------------|
// | `tau_step`              | number in [1e-4, 100]     | 0.1     | optical depth per march step against the local majorant |
// | `light_samples`         | integer in [1, 1024]      | 1       | transmittance estimates per light per step |
// | `transmittance`         | "ratio" or "shadow_map"   | "ratio" | to the lights: exact ratio tracking, or a deep shadow map (deterministic, biased by its resolution) for directional, point and spot lights and a march to a sampled point for area lights; the environment always uses ratio tracking |
// | `shadow_map_resolution` | integer in [8, 1024]      | 128     | shadow map nodes along the longest axis of the media's bounds |
#pragma once

#include "integrators/integrator.h"
#include "integrators/shadow_map.h"
#include "scene/lights.h"

namespace nimbus {

enum class Transmittance { ratio, shadow_map };

struct SingleSettings {
  double tau_step = 0.1;
  int light_samples = 1;
  Transmittance transmittance = Transmittance::ratio;
  int shadow_map_resolution = 128;
};

// The integrator block's own fields (strict), and back.
SingleSettings single_settings_from_json(const nlohmann::json& options, const std::string& where);
nlohmann::json to_json(const SingleSettings& s);

class SingleScatter final : public Integrator {
 public:
  SingleScatter(const SceneContext& context, SingleSettings settings);
  Rgb Li(const Ray& ray, Rng& rng, CameraSample* sample = nullptr) const override;
  // Li with `bounces` more rays gathered at the surface the ray ends on (Li: 1).
  Rgb trace(const Ray& ray, Rng& rng, CameraSample* sample, int bounces) const;
  nlohmann::json settings_json() const override { return to_json(s_); }

 private:
  // Transmittance from p towards light l (index into ctx_.lights) along the sampled direction.
  Rgb light_transmittance(size_t l, const Vec3& p, const LightSample& ls, Rng& rng) const;

  const SceneContext& ctx_;
  SingleSettings s_;
  std::vector<TransmittanceGrid> shadow_maps_;  // one per light of ctx_.lights when enabled
};

}  // namespace nimbus
