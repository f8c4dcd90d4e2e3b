// `octave`: the production multiple-scattering approximation of Wrenninge, Kulla and Lundqvist
// ("Oz: the great and volumetric", SIGGRAPH 2013 talk): a sum of N single-scattering passes, octave j
// with scattering scaled by a^j, extinction (camera and light side) by b^j and the phase function's
// eccentricity by c^j:
//     L = sum_{j<N} L_single(a^j sigma_s, b^j sigma_t, P with g -> c^j g).
// HG and double HG scale their g's; other phase functions are blended towards isotropic
// (c^j P + (1 - c^j) / (4 pi)), which scales their mean cosine by c^j. Octave 0 is `single`.
// Light transmittance: one deep shadow map per light of exp(-tau), octave j reads T^(b^j) (exact for
// the scaled extinction, which scales tau uniformly). The environment: one direction per octave sampled
// from that octave's phase function (an image: MIS with one map-sampled direction), marched
// transmittance. A baseline, not physics: a, b, c are knobs.
//
// Options (the JSON fields of the scene's integrator block besides type, spp, seed, max_events):
//
// | field                   | type                  | default | meaning                                      |
// |-------------------------|-----------------------|---------|----------------------------------------------|
// | `octaves`               | integer in [1, 32]    | 4       | N, the number of single-scattering passes     |
// | `a`                     | number in [0, 1]      | 0.5     | octave j scales scattering by a^j             |
// | `b`                     | number in [0, 1]      | 0.5     | octave j scales extinction by b^j             |
// | `c`                     | number in [0, 1]      | 0.5     | octave j scales the phase function's eccentricity by c^j |
// | `tau_step`              | number in [1e-4, 100] | 0.1     | optical depth per march step                  |
// | `shadow_map_resolution` | integer in [8, 1024]  | 64      | deep shadow map nodes along the longest axis  |
#pragma once

#include <vector>

#include "integrators/integrator.h"
#include "integrators/shadow_map.h"
#include "scene/lights.h"

namespace nimbus {

struct OctaveSettings {
  int octaves = 4;
  double a = 0.5, b = 0.5, c = 0.5;
  double tau_step = 0.1;
  int shadow_map_resolution = 64;
};

// The integrator block's own fields (strict), and back.
OctaveSettings octave_settings_from_json(const nlohmann::json& options, const std::string& where);
nlohmann::json to_json(const OctaveSettings& s);

// Medium phase function with its eccentricity scaled by `scale` (see above).
Phase scale_phase_eccentricity(const Phase& phase, double scale);

class OctaveIntegrator final : public Integrator {
 public:
  OctaveIntegrator(const SceneContext& context, OctaveSettings settings);
  Rgb Li(const Ray& ray, Rng& rng, CameraSample* sample = nullptr) const override;
  // Li with `bounces` more rays gathered at the surface the ray ends on (Li: 1).
  Rgb trace(const Ray& ray, Rng& rng, CameraSample* sample, int bounces) const;
  nlohmann::json settings_json() const override { return to_json(s_); }

 private:
  // One sample of every light at a march point, with its shadow-map transmittance (an area light's:
  // marched to the sampled point).
  struct LightSamples {
    std::vector<LightSample> ls;
    std::vector<Rgb> T;
    std::vector<bool> ok;  // false: the light contributes nothing here
  };
  // What octave j (extinction scale bj = b^j) scatters towards the camera at p, per unit of a^j dt.
  Rgb octave_scatter(int j, double bj, const Vec3& p, const Vec3& d, const MediumPoint& mp,
                     const LightSamples& lights, Rng& rng) const;
  // One sample of every light from p and its transmittance exp(-tau_l) (the map's, or marched to an
  // area light's sampled point); a light a surface hides is not ok.
  void sample_lights(const Vec3& p, Rng& rng, LightSamples* lights) const;

  const SceneContext& ctx_;
  OctaveSettings s_;
  std::vector<std::vector<Phase>> phases_;  // [octave][medium]
  std::vector<TransmittanceGrid> maps_;     // per light
};

}  // namespace nimbus
