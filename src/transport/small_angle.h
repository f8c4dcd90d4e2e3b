// The generalised forward propagator: multiple forward scattering for phase functions that are not
// Gaussian (Henyey-Greenstein, double HG, tabulated Mie), where the closed-form MFS kernel fails
// (../shared/notes/mfs-math.md, "The big caveat").  Pure math, no scene.  This is what the `mfs`
// renderer calls for the forward-scattered light along a path.
//
// Model ("gsa", generalised small-angle; validated in docs/validation/beam.md):
//  - ANGLE.  After a path with optical depths tau_s, tau_a the scattered light's direction density is
//        I(theta) = sum_l (2l + 1)/(4 pi) f_l P_l(cos theta),
//        f_l = exp(-tau_a) [exp(-tau_s (1 - chi_l)) - exp(-tau_s)],
//    chi_l the Legendre moments of the phase function (chi_0 = 1).  This is the exact solution on the
//    sphere of "n scatters are Poisson(tau_s) distributed along the path" (Funk-Hecke: convolving phase
//    functions multiplies their moments); for HG (chi_l = g^l) it is precisely the HG-Poisson series
//    sum_n Poisson(n; tau_s) HG(theta; g^n) exp(-tau_a) of the notes.  It neglects only that depth is
//    shorter than path length (forward-dominated light: a small effect, measured in the docs).
//  - SPACE.  The transverse spread uses the small-angle solution of the transfer equation for the
//    actual Fourier-transformed phase function Z(q) (seed eq. 4 with Z not expanded):
//        R(k) = exp(-tau_a - tau_s) [exp(tau_s Zbar(k)) - 1],  Zbar(k) = (1/z) int_0^z Z(k u) du,
//    whose inverse 2-D Fourier (Hankel) transform is the density per unit area (the n-scatter random walk
//    with Poisson(tau_s) scatters at uniform positions, summed).  Z(q) = 2 pi int P J0(q theta) sin theta
//    dtheta by quadrature for small q, and chi_l = Z(l + 1/2) (Hilb's asymptotics) for large q.  Radii are
//    in scattering mean free paths of the path (r_mfp = r tau_s / z for a path of physical length z, and a
//    density per mfp^2 times (tau_s / z)^2 is per physical area).  As in every small-angle solution all
//    scattered light is carried forward: radial_within(infinity) = total(), not forward_flux().
//  - LIMITS (docs/validation/beam.md): within a few % of photon Monte Carlo in on-axis radiance and
//    half-width where forward light dominates; it has no diffuse (returning) light, and it neglects the
//    extra absorption on lengthened paths (matters once z sqrt(a b theta2) ~ 1, see mfs_kernel.h).
//
// Use from a renderer (heterogeneous media: accumulate tau_s, tau_a along the path):
//     const ForwardPropagator prop(phase);              // once per phase function
//     const ForwardProfile p = prop.profile(tau_s, tau_a);
//     p.angular(theta)       // scattered radiance per sr at angle theta from the path's direction
//     p.radial(r_mfp)        // scattered power per mfp^2 at transverse distance r_mfp
//     p.total()              // all scattered, unabsorbed power
// Integrals of the radial profile are done by numerical Hankel transforms with an analytic tail.
#pragma once

#include <functional>
#include <memory>
#include <vector>

#include "media/phase.h"

namespace nimbus {

// Legendre moments chi_l = 2 pi int P(mu) P_l(mu) dmu, l = 0..L, chi_0 = 1; closed forms for HG and
// double HG, quadrature otherwise.  Stops once |chi_l| < tol for 8 consecutive l, or at l_cap.
std::vector<double> phase_legendre_moments(const Phase& phase, double tol = 1e-12, int l_cap = 6000);

// Four-point Gauss-Legendre nodes for integrals over the sphere of a function p(theta) that is zero outside
// [edges.front(), edges.back()]: panels no wider than hmax between consecutive edges (p's kinks go there);
// *mu (unless null) gets each node's cos theta, *wf its weight times p(theta) sin theta 2 pi (their sum: int p dOmega).
void sphere_quadrature(const std::function<double(double)>& p, const std::vector<double>& edges, double hmax,
                       std::vector<double>* mu, std::vector<double>* wf);

// The normalised Legendre moments chi_l = int p P_l dOmega / int p dOmega (l = 0..L, same stopping rule)
// of a function p(theta) >= 0 that is zero outside [edges.front(), edges.back()], by four-point
// Gauss-Legendre panels no wider than 1.5 / l_cap between consecutive edges (p's kinks go there).
// *mass, if given, receives int p dOmega.
std::vector<double> legendre_moments_of(const std::function<double(double)>& p,
                                        const std::vector<double>& edges, double tol, int l_cap,
                                        double* mass = nullptr);

// The per-component mean square deflection theta2 = <sin^2 theta> / 2 = (1 - chi_2) / 3 used to give a
// non-Gaussian phase function a Gaussian stand-in ((1 - g^2)/3 for HG); the Gaussian peak's own theta2.
double phase_theta2(const Phase& phase);

class ForwardPropagator;

// The scattered light after one path: what the renderer asks for.
class ForwardProfile {
 public:
  double total() const { return total_; }  // scattered unabsorbed power, all directions
  double forward_flux() const {
    return forward_flux_;
  }  // its flux through the plane (cos-weighted, theta < pi/2)
  // Plane-integrated radiance per steradian of the scattered light at polar angle theta [rad].
  double angular(double theta) const;
  // Scattered power within the cone of half-angle theta.
  double angular_within(double theta) const;
  // Forward scattered flux per unit area at transverse radius r [mean free paths].
  double radial(double r) const;
  // Forward scattered flux within radius r [mean free paths].
  double radial_within(double r) const;

 private:
  friend class ForwardPropagator;
  std::vector<double> f_;                                    // f_l
  std::shared_ptr<const std::vector<double>> cumulative_z_;  // int_0^(i) Z(q) dq at integer q
  double tau_s_ = 0.0, tau_a_ = 0.0, total_ = 0.0, forward_flux_ = 0.0;
  double spectrum(double k) const;        // R(k)
  double spectrum_slope(double k) const;  // dR/dk
  double zbar_and_z(double k, double* z_at) const;
};

// Built once per phase function (a few ms to ~0.5 s for a sharp tabulated Mie peak), then cheap.
class ForwardPropagator {
 public:
  explicit ForwardPropagator(const Phase& phase);
  // The scattered light after optical depths tau_s (scattering) and tau_a (absorption) along a path.
  ForwardProfile profile(double tau_s, double tau_a) const;
  const std::vector<double>& moments() const { return chi_; }

 private:
  std::vector<double> chi_;
  std::shared_ptr<const std::vector<double>> cumulative_z_;
};

}  // namespace nimbus
