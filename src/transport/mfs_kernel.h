// The multiple-forward-scattering (MFS) Green's function with a Gaussian forward peak, and the older
// small-angle forms it generalises (Dolin 1980; Tessendorf 1987/88). Pure functions, no scene.
//
// Everything is written from ../shared/notes/mfs-math.md (the seed paper's eqs. 12-16, corrected) and
// re-checked in tests/transport/mfs_kernel_test.cpp (numerical integrals, limits, Feynman-Kac walks).
//
// Variables.  A path of geometric length z [length] carries optical depths tau_s = int b ds (scattering)
// and tau_a = int a ds (absorption) along it.  For a homogeneous medium tau_s = b z, tau_a = a z; for a
// heterogeneous one the functions use the homogeneous medium with the same length and optical depths
// (seed sec. 5: the renderer marches in scattering lengths).  theta2 is the PER-COMPONENT mean square
// deflection <theta^2> of one scatter (seed eq. 5).  Directions are 2-D transverse vectors (small-angle
// components perpendicular to the axis), positions 2-D transverse offsets in the same length unit as z.
//
// Densities are per unit transverse area (d^2 r) and per steradian (d^2 v ~ dOmega), per unit source
// power, and exclude the unscattered light (it is the delta term exp(-tau_s - tau_a) apart).
#pragma once

#include <Imath/ImathVec.h>

namespace nimbus {

using Vec2 = Imath::V2d;

// h(x) = x - 2 tanh(x/2) (seed eq. 12 simplified); series x^3/12 - x^5/120 + ... below x = 0.1, where
// the closed form cancels catastrophically.
double mfs_h(double x);
// h(x) / x^3, finite at x = 0 (1/12).
double mfs_h_over_x3(double x);

// Which Gaussian small-angle form.
enum class GaussianModel {
  Dolin,  // Dolin 1980: angular variance theta2 b z, spatial theta2 b z^3 / 3, no asymptotic regime.
  Tes87,  // Tessendorf 1987/88 "improved" form: the oscillator kernel with T = theta2 b, L = ell.
  Mfs,    // The corrected seed kernel: T = theta2 b / (1 - exp(-b z)), L = 1 / sqrt(a T).
};

// The scales of the oscillator kernel along one path.
struct MfsScales {
  double z = 0.0;  // path length [length]
  double T = 0.0;  // angular diffusion rate [1/length] (T in the notes)
  double x = 0.0;  // z / L, with L = 1 / sqrt(a T) (x = 0 for a = 0, and always for Dolin)
  double W = 0.0;  // exp(-tau_a) (1 - exp(-tau_s)): scattered light before the path-lengthening loss
};
// Throws nimbus::Error on negative or non-finite inputs or z <= 0.
MfsScales mfs_scales(GaussianModel model, double z, double tau_s, double tau_a, double theta2);

// The corrected G_MFS in the paper's variables (seed eqs. 12-13 corrected; notes "Corrected closed
// form"): gamma and gamma_prime are the components of the arrival and departure directions
// perpendicular to the axis x - x' (|x - x'| = z).  Density per unit volume d^3x and per d^2 gamma.
double mfs_green(const MfsScales& s, const Vec2& gamma, const Vec2& gamma_prime);

// The same kernel in the fixed-axis form: a beam leaves the origin with transverse direction v0 along
// the +z axis; at depth z the density per unit area d^2 r and per d^2 v of scattered light at transverse
// position r with transverse direction v.  Its action is the oscillator action plus the constraint
// int gamma ds = r (notes: the extremal path with the constraint; see mfs_kernel.cpp for the algebra).
double mfs_fixed_axis(const MfsScales& s, const Vec2& r, const Vec2& v, const Vec2& v0);

// A joint Gaussian beam profile for a source along the axis (v0 = 0): per transverse component,
// direction v and position r are jointly Gaussian with the variances and covariance below.
struct GaussianBeam {
  double total = 0.0;       // scattered, unabsorbed power at depth z, per source photon
  double var_angle = 0.0;   // <v^2> per component [rad^2]
  double var_radius = 0.0;  // <r^2> per component [length^2]
  double cov = 0.0;         // <r v> per component [length]

  // Plane-integrated radiance per sr at polar angle theta (small-angle 2-D Gaussian in theta).
  double angular(double theta) const;
  // Power within the cone theta' < theta.
  double angular_within(double theta) const;
  // Angle-integrated power per unit area at radius r.
  double radial(double r) const;
  // Power within radius r.
  double radial_within(double r) const;
};

// The marginals of a model's kernel (notes "Marginals"): angular variance T L tanh x, spatial variance
// T L^3 [h(x) + tanh^2(x/2) tanh x], covariance L tanh(x/2) * angular variance, total W / cosh x.
// Dolin's form has total W (no path-lengthening loss), variances theta2 b z and theta2 b z^3 / 3.
GaussianBeam gaussian_beam(GaussianModel model, double z, double tau_s, double tau_a, double theta2);

}  // namespace nimbus
