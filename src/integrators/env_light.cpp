// The environment image's light (integrators/env_light.h): photon directions.
#include "integrators/env_light.h"

namespace nimbus {

Vec3 env_photon_direction(const SceneContext& ctx, double u1, double u2, double* pdf) {
  const EnvMap& map = *ctx.env_map;
  const double constant = 4.0 * kPi * std::max(0.0, luminance(ctx.environment));
  const double total = constant + map.luminance_integral();
  const double c = total > 0.0 ? constant / total : 1.0;  // the uniform part's share
  Vec3 wi;
  if (u1 < c) {
    wi = spherical_direction(1.0 - 2.0 * (u1 / c), 2.0 * kPi * u2, Vec3(0, 0, 1));
  } else {
    const EnvSample s = map.sample(std::min((u1 - c) / (1.0 - c), std::nextafter(1.0, 0.0)), u2);
    if (!(s.pdf > 0.0)) {
      *pdf = 0.0;
      return Vec3(0, 0, 1);
    }
    wi = s.wi;
  }
  *pdf = c / (4.0 * kPi) + (1.0 - c) * map.pdf(wi);
  return wi;
}

}  // namespace nimbus
