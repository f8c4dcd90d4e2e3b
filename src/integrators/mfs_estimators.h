// The estimators of the `mfs` integrator (integrators/mfs.h) as free functions: the camera-side state
// along the march, the light-side peak-only beam, and the radiance that one medium sends towards the
// camera from a march point y by each of the four kinds of path. Pure math on values the integrator
// looks up (shadow maps, beam grid, scatter grid); no scene. The equations (D1, D2, ...) are in
// docs/derivations.md; the code uses its names.
//
// All quantities are per channel (Rgb) where the media are chromatic; f, theta2 and the split are per
// medium. The floating-point operations are written in the order the images were made with: keep it.
#pragma once

#include <array>
#include <vector>

#include "core/math.h"
#include "core/sh.h"
#include "media/media.h"
#include "transport/phase_split.h"

namespace nimbus {

// 1 / cosh(sqrt(theta tau)): the extra loss on paths lengthened by peak deflections, for an accumulated
// angular diffusion theta = int theta2 dtau_p and loss depth tau (wide scatters and absorption)
// (docs/derivations.md eq. D5).
double path_lengthening(double theta, double tau);

// The peak split of the extinction at a point, summed over the media present (eq. D2):
//     sigma_peak = sum_i f_i sigma_s_i, sigma_theta = sum_i f_i theta2_i sigma_s_i,
//     sigma_red = sigma_t - sigma_peak (the reduced extinction: absorption and wide scatters),
//     sigma_drift = sum_i f_i (1 - chi_1,i) sigma_s_i (the rate at which peak scatters turn the mean
//     cosine of forward-carried light away from its axis, eq. D19; drift_i = 1 - chi_1 of medium i's
//     peak, none: 0).
struct MfsExtinction {
  Rgb sigma_t, sigma_peak, sigma_theta, sigma_red, sigma_drift{0.0};
};
MfsExtinction mfs_extinction(const MediumPoint& mp, const std::vector<double>& f,
                             const std::vector<double>& theta2, const std::vector<double>& drift = {});

// What the camera-side state gives at the march's sample point y.
struct CameraPoint {
  Rgb T_full;  // plain transmittance y -> camera (the forward-peak paths' last leg, eq. D7)
  Rgb T_cam;   // transmittance of light scattered at y: T_red (times eq. D5 or D19) or, light side, T_full
  Rgb tau_p;   // camera-side peak depth at y
  double sigma_red = 0.0;        // the reduced extinction at y (largest channel)
  double gradient_tilt = 0.0;    // camera_shift's k (eq. D17; 0: none)
  double gradient_spread = 0.0;  // and the footprint's lateral spread there (eq. D17b)
};

// The camera-side state along the march, from the camera to the current step's start (eqs. D2, D5, D10):
// T_full = exp(-tau_t), T_red = exp(-tau_red), the peak depth tau_p, the angular diffusion
// theta_p = int theta2 dtau_p, and the lateral-spread moments m_k = int theta2 sigma_peak s^k ds
// (k = 0, 1, 2, s from the ray's origin, largest channel); eq. D19's drift depth A = int sigma_drift ds
// and detour depth D = int sigma_red (e^A - 1) ds.
struct CameraPath {
  Rgb T_full{1.0}, T_red{1.0}, tau_p{0.0}, theta_p{0.0}, tau_red{0.0}, drift{0.0}, detour{0.0};
  double m0 = 0.0, m1 = 0.0, m2 = 0.0;

  // The state at the sample point y = jitter dt into the step (the march's offset).
  // light_side: light scattered at y goes to the camera unscattered (T_cam = T_full); otherwise it is
  // carried by the propagator (T_cam = T_red, times eq. D5 when path_lengthening, else times eq. D19's
  // fluence factor e^(A - D) when fluence).
  CameraPoint at(const MfsExtinction& k, double jitter, double dt, bool light_side, bool path_lengthening,
                 bool fluence = false) const;
  // Eq. D19's detour depth gained over the next h of path (the drift depth at its midpoint).
  Rgb detour_over(const MfsExtinction& k, double h) const;
  // The whole step [t - jitter dt, t + (1 - jitter) dt] (moments at its midpoint).
  void advance(const MfsExtinction& k, double t, double dt, double jitter);
  // Lateral standard deviation of the light that reaches the camera from depth t (eq. D10).
  double lateral_spread(double t) const;
  // The covariance (per component) of that light's lateral offset and its direction's deflection, and
  // the deflection's variance (eq. D16).
  double offset_deflection_covariance(double t) const { return t * m0 - m1; }
  double deflection_variance() const { return m0; }
};

// camera_tilt's offsets along one camera ray (eq. D16): points of the lateral footprint, a 2-D Gaussian
// perpendicular to d, one per march step. The azimuth starts at random and turns by the golden angle at
// each step; the radius runs through the midpoints of 16 equal-probability strata of the Rayleigh
// distribution (scaled so that its mean square is exact) from a random start, in strides of 5. Each step's
// offset has the footprint's azimuth and (stratified) radius, for one sincos per ray instead of a log and a
// sincos per step.
class FootprintProbe {
 public:
  static constexpr int kStrata = 16;
  FootprintProbe(const Vec3& d, double u1, double u2);
  // The next offset, at standard deviation sigma per component.
  Vec3 next(double sigma);

 private:
  Vec3 s_, t_;     // the plane perpendicular to d
  double c_, sn_;  // cos and sin of the current azimuth
  int k_;          // the current radius stratum
};

// camera_tilt (eq. D16): the camera-bound light's mean direction (reversed: the camera ray's d, deflected)
// given that its lateral offset at depth t is u (a draw of the footprint towards the side where the medium
// is), and the share of the camera-side peak depth left to the spread about it.
Vec3 survivor_direction(const CameraPath& cam, double t, const Vec3& d, const Vec3& u, double* residual);

// camera_shift (eq. D17): the camera-bound light's mean direction (reversed) d tilted towards wi, the
// direction towards a light whose beam grows at the rate sigma_red towards it, by
// k = cov(u, delta) sigma_red: normalize(d + k (wi - (wi . d) d)).
Vec3 gradient_tilted(const Vec3& d, const Vec3& wi, double k);
// camera_shift's k where the medium ends towards the light (eq. D17b): the footprint's Gaussian offset u
// (standard deviation s) along the tilt's direction, weighted by the beam's growth exp(a u) and cut at the
// medium's surface a distance D away along it (past it nothing scatters), has the mean a s^2 - s lambda(z),
// lambda = phi / Phi (the inverse Mills ratio) at z = (D - a s^2) / s; the tilt is k times that mean over
// the uncut a s^2, at least 0. k where D is infinite (or a, s are 0).
double truncated_gradient_tilt(double k, double a, double s, double D);
// y.gradient_tilt towards a light along wi (from d_s) cut by truncated_gradient_tilt at the medium's surface
// towards it: a = sigma_red sin theta (theta between d_s and wi), s = y.gradient_spread and D the light-side
// distance -ln(T_wide) / sigma_red (T_wide's largest channel) over sin theta (a surface normal to wi).
double cut_gradient_tilt(const CameraPoint& y, const Vec3& d_s, const Vec3& wi, const Rgb& T_wide);

// A point of the lateral footprint around the camera ray (direction d) at standard deviation sigma per
// component (eq. D10): a 2-D Gaussian offset perpendicular to d by Box-Muller from u1, u2 (eq. D14).
Vec3 lateral_offset(const Vec3& d, double sigma, double u1, double u2);

// One light's peak-only beam at y (light that has taken no wide scatter yet; eqs. D6, D8, D9).
struct LightBeam {
  Rgb T_light;  // plain transmittance to the light (shadow map)
  Rgb T_wide;   // reduced transmittance (T_light for beer_lambert), times R or eq. D5
  Rgb tau_ps;   // light-side peak depth: the beam's angular spread
  // peak_toward_camera: the traced beam's P_peak towards the camera (replaces peak_eff(tau_ps, mu) on camera
  // rays) where toward is set.
  bool toward = false;
  Rgb peak_toward{0.0};
  // wide_toward_camera: the traced beam's P_wide towards the camera over the straight model's wide factor at
  // the same samples (eq. D20), which multiplies the first wide scatter on camera rays where wide is set.
  bool wide = false;
  Rgb wide_ratio{1.0};
};
// From the shadow maps' T_light and T_wide, and from the beam grid where it covers y (traced: T_wide times
// R, and with mean_cos the spread from the beam's mean cosine, eq. D9; without it, or not traced, the
// straight beam's peak depth ln(T_wide / T_light), eq. D8); peak_moments: the medium's chi_l^peak;
// theta2: its peak's mean square angle. path_lengthening (forward light path only) applies eq. D5 to the
// straight beam. The traced beam's T_wide R is at most kMaxPeakTransmittance (see there).
//
// kMaxPeakTransmittance: the peak-only light, relative to the light's unattenuated beam, exceeds 1 only
// by its paths' lengthening (1 / cos of its spread): at most 1.16-1.34 on the suite's spheres and the
// Disney cloud. R = traced / straight is a ratio of two tallies, and in a medium of thin dense filaments
// (the smoke plume) a node's straight tally can be nearly empty: its photons' midpoint-rule loss fell
// far below the shadow map's where a deposit sample hit a dense voxel. R then reached 10^6 and T_wide R
// 10^5 (fireflies of 400x the pixel around them). The bound changes no image of the suite. (The beam grid
// bounds R itself by its plain tallies' ratio (BeamGrid::lookup), which keeps the smoke's and a dense cloud's
// T_wide R near what their photons carried; this bound stays as the last guard.)
inline constexpr double kMaxPeakTransmittance = 2.0;
LightBeam peak_only_beam(const Rgb& T_light, const Rgb& T_wide, bool traced, const Rgb& R,
                         const Rgb* mean_cos, const std::vector<double>& peak_moments, double theta2,
                         bool path_lengthening);

// The estimators: radiance per unit sigma_s_i that medium i (split, peak fraction f) sends towards the
// camera from y, for a light of weight E (radiance or irradiance per sample) at cosine mu between the
// light's and the camera-bound propagation directions.

// The first wide scatter at y (eq. D7, first term): E (1 - f) wide_eff(tau_p + tau_ps, mu) T_wide.
// tau_ps = 0 without light_blur.
Rgb first_wide_scatter(const Rgb& E, double f, const PhaseSplit& split, double mu, const Rgb& tau_p,
                       const Rgb& tau_ps, const Rgb& T_wide);
// The forward peak only (eq. D7, second term): E f peak_eff(tau, mu) T with (tau, T) = (tau_ps, T_wide),
// the last peak scatter of a path with no wide scatter; beer_lambert (eq. D7b): (tau_p, T_light), the
// first peak scatter of unscattered light.
Rgb forward_peak(const Rgb& E, double f, const PhaseSplit& split, double mu, const Rgb& tau, const Rgb& T);
// The same two at the tables' angle node a = PhaseSplit::angle(mu), found once for both.
Rgb first_wide_scatter(const Rgb& E, double f, const PhaseSplit& split, const PhaseSplit::Angle& a,
                       const Rgb& tau_p, const Rgb& tau_ps, const Rgb& T_wide);
Rgb forward_peak(const Rgb& E, double f, const PhaseSplit& split, const PhaseSplit::Angle& a, const Rgb& tau,
                 const Rgb& T);
// forward_side "light" (eq. D11): every scatter at y, whole phase function spread by the light side only:
// E T_wide [(1 - f) wide_eff(tau_ps, mu) + f peak_eff(tau_ps, mu)].
Rgb light_side_scatter(const Rgb& E, double f, const PhaseSplit& split, double mu, const Rgb& tau_ps,
                       const Rgb& T_wide);

// The Legendre moments of the last wide scatter for the scatter grid's Funk-Hecke sum (eq. D12), bands
// l < bands: chi_l = chi_l^wide exp(-tau_p (1 - chi_l^peak)) (camera-side blur, eq. D3) ...
std::array<Rgb, kShMaxBands> blurred_wide_moments(const PhaseSplit& split, const Rgb& tau_p, int bands);
// ... or, forward_side "light", the whole phase function's f chi_l^peak + (1 - f) chi_l^wide.
std::array<Rgb, kShMaxBands> whole_phase_moments(const PhaseSplit& split, double f, int bands);

}  // namespace nimbus
