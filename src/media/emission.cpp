// Emission in media (media/emission.h).
#include "media/emission.h"

#include <cmath>

#include "media/blackbody.h"

namespace nimbus {

namespace {

double sample(const DensityGrid& g, const Vec3& gw) { return g.density_index(g.world_to_index(gw)); }

// Conservative max of grid g over the grid-world box.
double box_max(const DensityGrid& g, const Bounds& gw_box) {
  const Bounds ib =
      bounds_of_mapped_box(gw_box.lo, gw_box.hi, [&](const Vec3& p) { return g.world_to_index(p); });
  Vec3 lo = ib.lo, hi = ib.hi;
  for (int a = 0; a < 3; ++a) lo[a] = std::floor(lo[a]) - 1.0, hi[a] = std::ceil(hi[a]) + 1.0;
  return g.max_density_index(lo, hi);
}

}  // namespace

MediumEmissionField::MediumEmissionField(const Medium& m) : e_(m.emission), sigma_a_(m.sigma_a) {
  const EmissionGrids* g = e_.grids.get();
  const bool has_temperature = g && g->temperature && e_.intensity > 0.0 && max_component(sigma_a_) > 0.0;
  emits_ = max_component(e_.radiance) > 0.0 || has_temperature;
  tints_ = g && g->color[0];
}

Rgb MediumEmissionField::emission(const Vec3& gw, double density) const {
  if (!emits_) return Rgb(0.0);
  const EmissionGrids* g = e_.grids.get();
  Rgb j(0.0);
  if (max_component(e_.radiance) > 0.0)
    j = e_.radiance * (g && g->emission ? sample(*g->emission, gw) : density);
  if (g && g->temperature && density > 0.0) {
    const double T = e_.temperature_scale * sample(*g->temperature, gw) + e_.temperature_offset;
    j += sigma_a_ * (e_.intensity * density) * blackbody_rgb(T);
  }
  return j;
}

Rgb MediumEmissionField::tint(const Vec3& gw) const {
  if (!tints_) return Rgb(1.0);
  Rgb c;
  for (int k = 0; k < 3; ++k) c[k] = std::clamp(sample(*e_.grids->color[k], gw), 0.0, 1.0);
  return c;
}

bool MediumEmissionField::may_emit(const Bounds& gw_box, double max_density) const {
  if (!emits_) return false;
  const EmissionGrids* g = e_.grids.get();
  if (max_component(e_.radiance) > 0.0) {
    if (g && g->emission ? box_max(*g->emission, gw_box) > 0.0 : max_density > 0.0) return true;
  }
  return g && g->temperature && max_density > 0.0 && e_.intensity > 0.0 && max_component(sigma_a_) > 0.0;
}

Bounds MediumEmissionField::grid_bounds() const {
  Bounds b;
  const EmissionGrids* g = e_.grids.get();
  if (!g) return b;
  for (const auto* grid : {g->emission.get(), g->temperature.get(), g->color[0].get()})
    if (grid) b.extend(grid->world_bounds());
  return b;
}

Rgb emission_over_step(const Rgb& j, const Rgb& T0, const Rgb& T1, double dt) {
  Rgb out(0.0);
  for (int c = 0; c < 3; ++c) {
    if (j[c] == 0.0 || !(T0[c] > 0.0)) continue;
    const double r = T1[c] / T0[c];
    // (1 - r) / -ln(r): the mean of T / T0 over the step; 1 - x/2 for a thin step.
    const double mean = r > 1.0 - 1e-6 ? 1.0 - 0.5 * (1.0 - r) : r > 0.0 ? (1.0 - r) / -std::log(r) : 0.0;
    out[c] = j[c] * dt * T0[c] * mean;
  }
  return out;
}

}  // namespace nimbus
