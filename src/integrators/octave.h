// `octave`: the production multiple-scattering approximation of Wrenninge, Kulla and Lundqvist
// ("Oz: the great and volumetric", SIGGRAPH 2013 talk): a sum of N single-scattering passes, octave j
// with scattering scaled by a^j, extinction (camera and light side) by b^j and the phase function's
// eccentricity by c^j:
//     L = sum_{j<N} L_single(a^j sigma_s, b^j sigma_t, P with g -> c^j g).
// HG and double HG scale their g's; other phase functions are blended towards isotropic
// (c^j P + (1 - c^j) / (4 pi)), which scales their mean cosine by c^j. Octave 0 is `single`.
// Light transmittance: one deep shadow map per light of exp(-tau), octave j reads T^(b^j) (exact for
// the scaled extinction, which scales tau uniformly). The environment: one direction per octave sampled
// from that octave's phase function, marched transmittance. A baseline, not physics: a, b, c are knobs.
#pragma once

#include <vector>

#include "integrators/integrator.h"
#include "integrators/shadow_map.h"

namespace nimbus {

struct OctaveSettings {
  int octaves = 4;
  double a = 0.5, b = 0.5, c = 0.5;
  double tau_step = 0.1;
  int shadow_map_resolution = 64;
};

OctaveSettings parse_octave_settings(const nlohmann::json& options, const std::string& where, bool strict);

// Medium phase function with its eccentricity scaled by `scale` (see above).
Phase scale_phase_eccentricity(const Phase& phase, double scale);

class OctaveIntegrator final : public Integrator {
 public:
  OctaveIntegrator(const SceneContext& context, OctaveSettings settings);
  Rgb sample(double px, double py, Rng& rng) const override;
  Rgb radiance(const Vec3& o, const Vec3& d, Rng& rng) const;

 private:
  const SceneContext& ctx_;
  OctaveSettings s_;
  std::vector<std::vector<Phase>> phases_;  // [octave][medium]
  std::vector<TransmittanceGrid> maps_;     // per light
};

}  // namespace nimbus
