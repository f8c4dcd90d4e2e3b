// Time-resolved transport (issue 14): time bins from the command line and the closed forms that judge
// the photon Monte Carlo's time tallies.  Time is path length times the refractive index n (c = 1 in
// vacuum, so with n = 1 time is the path length in the medium), in the length unit of the run.
#pragma once

#include <string>
#include <vector>

namespace nimbus {

// The most time bins one run of beam, slab or lidar may ask for (each costs a tally per batch, per plane
// and per face); the same number as a render's kMaxTimeBins (nimbus/scene.h).
inline constexpr size_t kMaxTimeEdgeBins = 100000;

// Time-bin edges from `t0,t1,...` (at least two, strictly increasing) or `lo:hi:N` (N equal bins from lo
// to hi).  Edges must be finite and >= 0, at most kMaxTimeEdgeBins bins.  Errors name `what`.
std::vector<double> parse_time_edges(const std::string& what, const std::string& spec);

// --- Diffusion: time-resolved diffuse reflectance of a semi-infinite medium -------------------------
// Patterson, Chance & Wilson 1989 (Appl. Opt. 28, 2331), integrated over the surface, with the
// extrapolated boundary (Haskell et al. 1994; Contini et al. 1997 eq. 36, flux form): an isotropic point
// source at depth z0 = 1 / mu_s' and its image at -(z0 + 2 z_e), z_e = 2 A D, D = 1 / (3 (mu_a + mu_s')).
// Reflectance per unit time at time t (c = 1 / n in the medium, t in units of length):
//   R(t) = (4 pi D v)^(-1/2) t^(-3/2) exp(-mu_a v t) 1/2 [z0 e^(-z0^2/(4 D v t)) + z+ e^(-z+^2/(4 D v t))]
// with v = 1 / n, z+ = z0 + 2 z_e.  A = 1 for matched boundaries (n = 1).
double diffusion_reflectance_rate(double t, double mu_s_prime, double mu_a, double n, double A = 1.0);

// --- The corrected MFS kernel's delay distribution (docs/validation/time.md) ------------------------
// For a pencil beam and the scattered light crossing the plane at depth z (integrated over the plane
// and over angle), the Gaussian path measure of the kernel gives the delay tau = s - z = 1/2 int |gamma|^2
// the Laplace transform  E[exp(-p tau)] = 1 / cosh(z sqrt(p T))  (relative to the light at p = 0), with
// T = theta2 b / (1 - exp(-b z)) and theta2 the per-component <theta^2> of one scatter.  Absorption a
// weights each path by exp(-a tau), so the weighted delay has cumulants from ln cosh(z sqrt((a + p) T)):
//   mean     = T L z tanh(x) / 2,                    x = z / L, L = 1 / sqrt(a T)   (-> T z^2 / 2, a = 0)
//   variance = L^4 T^2 [x tanh x - x^2 sech^2 x] / 4                             (-> T^2 z^4 / 6, a = 0)
struct DelayMoments {
  double mean = 0.0;      // <s - z> [length]
  double variance = 0.0;  // <(s - z)^2> - mean^2 [length^2]
};
// z [length], b and a [1/length], theta2 per component [rad^2].  Throws nimbus::Error on bad input.
DelayMoments mfs_delay_moments(double z, double b, double a, double theta2);

// The exact small-angle answer it approximates, for a = 0: deflections of per-component variance theta2
// (Gaussian) at the events of a Poisson process of rate b; tau = 1/2 int_0^z |sum of deflections|^2.
// With A_ik = min(z - t_i, z - t_k), tau = theta2-weighted quadratic form: E[tau | times] = theta2 tr A,
// Var[tau | times] = theta2^2 tr A^2, and Campbell's formulas over the Poisson times give, for all light,
//   mean = theta2 b z^2 / 2,  <tau^2> - mean^2 = theta2^2 (2 b z^3 / 3 + b^2 z^4 / 6);
// returned conditioned on at least one scatter (the unscattered light has tau = 0).  The Gaussian
// measure's mean is the same; its variance lacks the Poisson term 2 b z^3 / 3 (relative 4 / (b z)).
DelayMoments poisson_delay_moments(double z, double b, double theta2);

// The shape: with u = tau / (T z^2), 1 / cosh(sqrt(q)) is the Laplace transform of
//   f(u) = pi sum_k (-1)^k (2k + 1) exp(-(k + 1/2)^2 pi^2 u)            (residues; used for u >= 0.25)
//        = sum_k (-1)^k (2k + 1) exp(-(2k + 1)^2 / (4 u)) / sqrt(pi u^3)  (image series; u < 0.25)
// (the exit time of a Brownian motion from an interval).  The delay density of the scattered light
// crossing the plane, per unit delay and per source photon, absorption included, is
//   exp(-a z) (1 - exp(-b z)) exp(-a tau) f(tau / (T z^2)) / (T z^2),
// whose integral over tau is the kernel's total W / cosh(z / L).
double mfs_delay_density(double tau, double z, double b, double a, double theta2);
// Its integral over [lo, hi) (Gauss-Legendre on 32 sub-intervals; hi may be infinite).
double mfs_delay_within(double lo, double hi, double z, double b, double a, double theta2);

}  // namespace nimbus
