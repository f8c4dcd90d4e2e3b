// A flat water surface between the lidar (air, index 1) and the slab (index n): exact unpolarised Fresnel
// reflectance, and the refracted path from a point in the water to a point in the air with the ray
// tube's spreading (issue 14, section 2; docs/validation/lidar.md).
#pragma once

namespace nimbus {

// Unpolarised Fresnel reflectance (R_s + R_p) / 2 of light arriving with cos_i = cos of the angle to the
// normal from a medium of index n_i into one of n_t, eta = n_t / n_i > 0; 1 beyond the critical angle
// (total internal reflection).  The transmittance is 1 - R (energy, no absorption at the surface).
double fresnel_reflectance(double cos_i, double eta);

// The refracted path from a point h > 0 below the surface to a point d > 0 above it, rho >= 0 apart
// horizontally, through the surface of a medium of index n >= 1 below air (Snell: n sin theta_w =
// sin theta_a).  a: the horizontal run in the water; cos_w, cos_a: the path's angles to the vertical in
// water and air; L_w, L_a: the lengths of its two parts.  spread = dA / dOmega_w: the horizontal area
// at the upper point per unit solid angle of directions leaving the lower point,
//   (h / cos_w + n d / cos_a) (h / cos_w^2 + n d cos_w / cos_a^3)
// (cylindrical coordinates: rho(theta_w) = h tan theta_w + d tan theta_a); (h + d)^2 / cos^3 for n = 1,
// (h + n d)^2 on the vertical.  A source of intensity I below gives the irradiance I T / spread on the
// horizontal plane above (T = 1 - R at the surface).
struct RefractedPath {
  double a = 0.0, cos_w = 1.0, cos_a = 1.0, L_w = 0.0, L_a = 0.0, spread = 0.0;
};
RefractedPath refracted_path(double h, double d, double rho, double n);

}  // namespace nimbus
