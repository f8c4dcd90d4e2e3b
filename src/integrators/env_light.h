// The environment image's light at a point (scene/env_map.h), shared by the integrators: one direction
// drawn from the map by luminance and one drawn by the point's own scattering (the phase function in a
// medium, the cosine on a diffuse surface), combined by multiple importance sampling with the power
// heuristic (Veach 1997, sec. 9.2.4; pbrt-v4 sec. 2.2.3):
//     L ~ sum_s w_s(wi_s) L_map(wi_s) f(wi_s) T(wi_s) / p_s(wi_s),   w_s = p_s^2 / (p_map^2 + p_f^2),
// unbiased for any f and T, and close to the better of the two where the map is peaked (a sun) or the
// scattering is (a forward phase function). The constant environment is not handled here.
#pragma once

#include "core/math.h"
#include "core/rng.h"
#include "media/phase.h"
#include "scene/context.h"
#include "scene/env_map.h"

namespace nimbus {

// Veach's power heuristic (beta = 2) for one sample of each of two strategies.
inline double power_heuristic(double pdf_a, double pdf_b) {
  const double a = pdf_a * pdf_a, b = pdf_b * pdf_b;
  return a + b > 0.0 ? a / (a + b) : 0.0;
}

// The MIS estimate of int L_map(wi) f(wi) T(wi) dwi at one point. u1, u2: the map's sample; wb: the
// direction the point's own sampler drew (density pdf_b(wb)). f(wi) -> Rgb: the scattering function
// (times any path weight), pdf_b(wi) -> double: the density of the point's own sampler,
// T(wi) -> Rgb: the transmittance towards the map along wi (called only where the rest is non-zero).
template <typename F, typename PdfB, typename Transmittance>
Rgb env_map_mis(const EnvMap& map, double u1, double u2, const Vec3& wb, F&& f, PdfB&& pdf_b,
                Transmittance&& T) {
  Rgb L(0.0);
  // A direction drawn from the map.
  const EnvSample es = map.sample(u1, u2);
  if (es.pdf > 0.0 && max_component(es.L) > 0.0) {
    const Rgb fv = f(es.wi);
    if (max_component(fv) > 0.0) L += es.L * fv * T(es.wi) * (power_heuristic(es.pdf, pdf_b(es.wi)) / es.pdf);
  }
  // The point's own direction.
  const double pb = pdf_b(wb);
  if (pb > 0.0) {
    const Rgb Le = map.eval(wb);
    if (max_component(Le) > 0.0) {
      const Rgb fv = f(wb);
      if (max_component(fv) > 0.0) L += Le * fv * T(wb) * (power_heuristic(pb, map.pdf(wb)) / pb);
    }
  }
  return L;
}

// The environment image's light scattered at a medium point towards -d (d: the ray's direction of
// travel) per unit sigma_s: env_map_mis with the phase function as f and as the second sampler.
// Four uniform numbers.
template <typename Transmittance>
Rgb medium_env_map_light(const EnvMap& map, const Phase& phase, const Vec3& d, Rng& rng, Transmittance&& T) {
  const double u1 = rng.uniform(), u2 = rng.uniform(), v1 = rng.uniform(), v2 = rng.uniform();
  auto pdf = [&](const Vec3& wi) { return phase_eval(phase, dot(d, wi)); };
  return env_map_mis(
      map, u1, u2, phase_sample(phase, d, v1, v2), [&](const Vec3& wi) { return Rgb(pdf(wi)); }, pdf, T);
}

// A direction wi towards the environment (ctx.env_map set) for photon emission: uniform on the sphere
// with the constant environment's share of the luminance integral, else from the map; *pdf its
// density per solid angle (the mixture's).
Vec3 env_photon_direction(const SceneContext& ctx, double u1, double u2, double* pdf);

}  // namespace nimbus
