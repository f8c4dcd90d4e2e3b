// The generalised small-angle propagator's (`gsa`: HG, double HG, Mie) delay distribution (issue 14,
// docs/validation/time.md "The generalised propagator's delay").  Pure math, no scene.
//
// The propagator (small_angle.h) carries the scattered light as deflections theta (2-D, the polar
// deflection angle as its length, the variable of its Fourier transform Z(q)) drawn from the phase
// function at the events of a Poisson process of rate b.  The delay of a path reaching depth z is, to
// leading order in the angles, tau = s - z = 1/2 int_0^z |gamma|^2, gamma the sum of the deflections so
// far.  With m2 = <theta^2>, m4 = <theta^4> of ONE deflection (both transverse components together)
// Campbell's formulas over the Poisson times give, for all the light (derivation in time.md):
//     <tau>     = m2 b z^2 / 4
//     Var tau   = m4 b z^3 / 12 + m2^2 b^2 z^4 / 24
// (Gaussian deflections of per-component variance theta2: m2 = 2 theta2, m4 = 8 theta2^2, which is
// poisson_delay_moments of time_resolved.h).  The unscattered light has tau = 0; the moments returned are
// those of the scattered light (conditioned on at least one scatter).
//
// SHAPE: no closed form for a general deflection law; the `gsa` rows of `nimbus beam --time-edges` use a
// MOMENT-MATCHED GAMMA LAW (shape k = mean^2 / var, scale var / mean), exact in its first two moments
// (without absorption) and nothing more.  Absorption a weights each path by exp(-a tau); the gamma law
// tilted by exp(-a tau) is again gamma (scale / (1 + a scale)) with weight (1 + a scale)^-k: an
// approximation (it tilts the matched law, not the true one), fine while a tau << 1.
#pragma once

#include "media/phase.h"
#include "transport/time_resolved.h"

namespace nimbus {

// Moments of one deflection's polar angle theta [rad] under the phase function.
struct DeflectionMoments {
  double m2 = 0.0;  // <theta^2> [rad^2]
  double m4 = 0.0;  // <theta^4> [rad^4]
};
// Quadrature over theta in [0, pi] (geometric panels from 1e-7 rad); a Gaussian peak uses its
// small-angle moments 2 theta2 and 8 theta2^2 (the same as the MFS kernel's closed form).
DeflectionMoments deflection_moments(const Phase& phase);

// Delay moments of the scattered light at depth z [length] for scattering b [1/length], no absorption.
// Throws nimbus::Error on bad input.
DelayMoments compound_poisson_delay_moments(double z, double b, const DeflectionMoments& m);

// The moment-matched gamma law of the gsa rows, absorption included.
struct GammaDelayLaw {
  double weight = 0.0;  // scattered light per source photon: exp(-a z) (1 - exp(-b z)) (1 + a scale0)^-k
  double shape = 0.0;   // k
  double scale = 0.0;   // [length], after the tilt
  double mean() const { return shape * scale; }
  double variance() const { return shape * scale * scale; }
  // Weight with delay in [lo, hi) (hi may be infinite).
  double within(double lo, double hi) const;
};
GammaDelayLaw gsa_delay_law(double z, double b, double a, const DeflectionMoments& m);

// The regularised lower incomplete gamma function P(k, x) = gamma(k, x) / Gamma(k), k > 0, x >= 0
// (power series below x = k + 1, continued fraction for Q = 1 - P above; Abramowitz & Stegun 6.5.29, 6.5.31).
double regularized_gamma_p(double k, double x);

}  // namespace nimbus
