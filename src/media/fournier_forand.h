// The Fournier-Forand phase function of ocean particles (Fournier & Forand 1994, in the form of
// Mobley, Sundman & Boss 2002, Appl. Opt. 41, 1035, eq. 5; CDF of Fournier & Jonasz 1999):
//
//   P(psi) = 1 / (4 pi (1 - delta)^2 delta^nu) [nu (1 - delta) - (1 - delta^nu)
//              + (delta (1 - delta^nu) - nu (1 - delta)) / sin^2(psi / 2)]
//          + (1 - delta_180^nu) / (16 pi (delta_180 - 1) delta_180^nu) (3 cos^2 psi - 1),
//   nu = (3 - mu) / 2,  delta = 4 sin^2(psi / 2) / (3 (n - 1)^2),  delta_180 = delta(pi),
//
// for particles of relative refractive index n and a Junge (hyperbolic) size distribution of slope mu.
// The first term integrates to 1 on the sphere and the second to 0, so P is normalised exactly; it is
// infinite (integrably, like psi^(mu - 5)) at psi = 0.  Mobley et al. pick n from mu,
// n = 1.01 + 0.1542 (mu - 3), and mu from the backscatter fraction B; the Petzold average particle is
// n = 1.10, mu = 3.5835 (B = 0.0183).
//
// The evaluation here keeps the removable singularity at delta = 1 (a cone of a few degrees) exact: the
// bracket over (1 - delta)^2 is rewritten with h(x) = (delta^nu - 1 + nu x) / x^2, x = 1 - delta (a
// series for small |x|).
#pragma once

#include "nimbus/phase.h"

namespace nimbus {

// Valid parameters: n in (1, 1.5], mu in (3, 5].
bool ff_parameters_valid(double n, double mu);
// Density per sr at cos_theta (propagation directions); +infinity at cos_theta = 1.
double ff_eval(double cos_theta, double n, double mu);
// The same at the angle theta [rad], accurate for small angles (where cos theta rounds to 1).
double ff_eval_theta(double theta, double n, double mu);
// Probability of a deflection within theta [rad] (Fournier & Jonasz 1999); 0 at 0, 1 at pi.
double ff_cdf(double theta, double n, double mu);
// Backscatter fraction 1 - ff_cdf(pi / 2).
double ff_backscatter_fraction(double n, double mu);
// Mobley et al. 2002: n(mu) = 1.01 + 0.1542 (mu - 3), and the mu in (3, 5] on that curve whose
// backscatter fraction is b (bisection; throws nimbus::Error when b is out of the curve's reach).
double ff_mobley_n(double mu);
double ff_mobley_mu(double backscatter_fraction);

// The phase function as a table (about 2560 nodes: 0, geometric with ratio 1.01 from 1e-7 to 0.05 rad,
// then steps <= 0.0025 rad), values of ff_eval except at theta = 0, where the node value makes the first
// panel's probability the closed-form ff_cdf(1e-7); normalised and sampled by make_tabulated_phase
// (inverse CDF of the table).
TabulatedPhase make_ff_phase(double n, double mu);

}  // namespace nimbus
