// The `mfs` estimators (see mfs_estimators.h); equations D1 .. D12 of docs/derivations.md.
#include "integrators/mfs_estimators.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace nimbus {

double path_lengthening(double theta, double tau) {
  // docs/derivations.md eq. D5: 1 / cosh(x) = 2 e^-x / (1 + e^-2x), x = sqrt(theta tau).
  const double x = std::sqrt(std::max(0.0, theta * tau));
  const double e = std::exp(-x);
  return 2.0 * e / (1.0 + e * e);
}

MfsExtinction mfs_extinction(const MediumPoint& mp, const std::vector<double>& f,
                             const std::vector<double>& theta2, const std::vector<double>& drift) {
  // eq. D2: the peak part of each medium's scattering is not extinction for forward-carried light.
  MfsExtinction k;
  k.sigma_t = mp.sigma_t();
  k.sigma_peak = Rgb(0.0);
  k.sigma_theta = Rgb(0.0);
  k.sigma_drift = Rgb(0.0);
  for (int i = 0; i < mp.count; ++i) {
    k.sigma_peak += mp.sigma_s_i[i] * f[i];
    k.sigma_theta += mp.sigma_s_i[i] * (f[i] * theta2[i]);
    if (size_t(i) < drift.size()) k.sigma_drift += mp.sigma_s_i[i] * (f[i] * drift[size_t(i)]);
  }
  k.sigma_red = k.sigma_t - k.sigma_peak;
  return k;
}

CameraPoint CameraPath::at(const MfsExtinction& k, double jitter, double dt, bool light_side,
                           bool lengthening, bool fluence) const {
  CameraPoint y;
  y.T_full = T_full * exp_channels(-k.sigma_t * (jitter * dt));
  if (light_side) {
    y.T_cam = y.T_full;
  } else {
    // Light scattered at y is carried to the camera by the propagator: only absorption and wide
    // scatters remove it (eq. D2); its lengthened paths lose eq. D5, or its fluence is eq. D19's.
    const double h = jitter * dt;
    y.T_cam = T_red * exp_channels(-k.sigma_red * h);
    if (lengthening) {
      for (int c = 0; c < 3; ++c)
        y.T_cam[c] *= path_lengthening(theta_p[c] + k.sigma_theta[c] * jitter * dt,
                                       tau_red[c] + k.sigma_red[c] * jitter * dt);
    } else if (fluence) {
      y.T_cam *= exp_channels(drift + k.sigma_drift * h - detour - detour_over(k, h));
    }
  }
  y.tau_p = tau_p + k.sigma_peak * (jitter * dt);
  y.sigma_red = max_component(k.sigma_red);
  return y;
}

Rgb CameraPath::detour_over(const MfsExtinction& k, double h) const {
  return k.sigma_red * (exp_channels(drift + k.sigma_drift * (0.5 * h)) - Rgb(1.0)) * h;
}

void CameraPath::advance(const MfsExtinction& k, double t, double dt, double jitter) {
  T_full *= exp_channels(-k.sigma_t * dt);
  T_red *= exp_channels(-k.sigma_red * dt);
  tau_p += k.sigma_peak * dt;
  theta_p += k.sigma_theta * dt;
  tau_red += k.sigma_red * dt;
  // eq. D19's detour depth over the step (the drift depth at its midpoint), then the drift depth.
  if (max_component(k.sigma_drift) > 0.0 || max_component(drift) > 0.0) {
    detour += detour_over(k, dt);
    drift += k.sigma_drift * dt;
  }
  // eq. D10's moments, by the midpoint rule over the step.
  const double a = max_component(k.sigma_theta) * dt, tm = t + (0.5 - jitter) * dt;
  m0 += a;
  m1 += a * tm;
  m2 += a * tm * tm;
}

double CameraPath::lateral_spread(double t) const {
  // eq. D10: variance t^2 m0 - 2 t m1 + m2 = int theta2 sigma_peak (t - s)^2 ds.
  return std::sqrt(std::max(0.0, t * t * m0 - 2.0 * t * m1 + m2));
}

Vec3 survivor_direction(const CameraPath& cam, double t, const Vec3& d, const Vec3& u, double* residual) {
  // (u, delta) per component jointly Gaussian: var(u) = v (eq. D10), cov(u, delta) = c, var(delta) = m0,
  // so E[delta | u] = (c / v) u and var(delta | u) = m0 - c^2 / v.
  const double s = cam.lateral_spread(t), v = s * s, c = cam.offset_deflection_covariance(t),
               m0 = cam.deflection_variance();
  if (!(v > 0.0) || !(m0 > 0.0)) {
    *residual = 1.0;
    return d;
  }
  *residual = std::clamp(1.0 - c * c / (v * m0), 0.0, 1.0);
  return normalize(d + u * (c / v));
}

Vec3 gradient_tilted(const Vec3& d, const Vec3& wi, double k) {
  return normalize(d + (wi - d * dot(wi, d)) * k);
}

double truncated_gradient_tilt(double k, double a, double s, double D) {
  if (!(a > 0.0) || !(s > 0.0) || !(D < std::numeric_limits<double>::infinity())) return k;
  const double z = (D - a * s * s) / s;
  // lambda(z) = phi(z) / Phi(z); for z far below 0, Phi's tail makes it -z (its asymptote, to 1 / z^2).
  const double Phi = 0.5 * std::erfc(-z / std::sqrt(2.0));
  const double lambda = Phi > 1e-300 ? std::exp(-0.5 * z * z) / std::sqrt(2.0 * kPi) / Phi : -z;
  return k * std::max(0.0, 1.0 - lambda / (a * s));
}

double cut_gradient_tilt(const CameraPoint& y, const Vec3& d_s, const Vec3& wi, const Rgb& T_wide) {
  if (!(y.gradient_tilt > 0.0) || !(y.sigma_red > 0.0)) return y.gradient_tilt;
  const double mu = dot(d_s, wi), sin_t = std::sqrt(std::max(0.0, 1.0 - mu * mu));
  const double depth = -std::log(std::clamp(max_component(T_wide), 1e-300, 1.0)) / y.sigma_red;
  return truncated_gradient_tilt(y.gradient_tilt, y.sigma_red * sin_t, y.gradient_spread,
                                 depth / std::max(sin_t, 1e-3));
}

namespace {

// The Rayleigh distribution's strata midpoints, sqrt(-2 ln(1 - (k + 1/2) / n)), scaled to mean square 2.
std::array<double, FootprintProbe::kStrata> rayleigh_strata() {
  std::array<double, FootprintProbe::kStrata> r{};
  double m2 = 0.0;
  for (int k = 0; k < FootprintProbe::kStrata; ++k) {
    r[size_t(k)] = std::sqrt(-2.0 * std::log(1.0 - (k + 0.5) / FootprintProbe::kStrata));
    m2 += r[size_t(k)] * r[size_t(k)] / FootprintProbe::kStrata;
  }
  for (double& x : r) x *= std::sqrt(2.0 / m2);
  return r;
}

}  // namespace

FootprintProbe::FootprintProbe(const Vec3& d, double u1, double u2) {
  const Frame fr(d);
  s_ = fr.s;
  t_ = fr.t;
  c_ = std::cos(2.0 * kPi * u1);
  sn_ = std::sin(2.0 * kPi * u1);
  k_ = std::min(kStrata - 1, int(u2 * kStrata));
}

Vec3 FootprintProbe::next(double sigma) {
  static const std::array<double, kStrata> radius = rayleigh_strata();
  static const double cg = std::cos(kPi * (3.0 - std::sqrt(5.0))),
                      sg = std::sin(kPi * (3.0 - std::sqrt(5.0)));
  const double r = sigma * radius[size_t(k_)];
  const Vec3 u = s_ * (r * c_) + t_ * (r * sn_);
  const double c = c_ * cg - sn_ * sg;  // the golden angle further
  sn_ = sn_ * cg + c_ * sg;
  c_ = c;
  k_ = (k_ + 5) % kStrata;
  return u;
}

Vec3 lateral_offset(const Vec3& d, double sigma, double u1, double u2) {
  if (!(sigma > 0.0)) return Vec3(0.0);
  const double r = sigma * std::sqrt(-2.0 * std::log(1.0 - u1)), phi = 2.0 * kPi * u2;
  const Frame fr(d);
  return fr.s * (r * std::cos(phi)) + fr.t * (r * std::sin(phi));
}

LightBeam peak_only_beam(const Rgb& T_light, const Rgb& T_wide, bool traced, const Rgb& R,
                         const Rgb* mean_cos, const std::vector<double>& peak_moments, double theta2,
                         bool lengthening) {
  LightBeam b{T_light, T_wide, Rgb(0.0)};
  const double one_minus_chi1 = 1.0 - (peak_moments.size() > 1 ? peak_moments[1] : 1.0);
  // A channel equal to the one before it in every input takes that channel's values (grey media: one log
  // instead of three; the same values bit for bit).
  for (int c = 0; c < 3; ++c) {
    if (traced && mean_cos) {
      // eq. D9: the peak depth whose spread has the traced beam's mean cosine (eq. D3 at l = 1:
      // mean_cos = exp(-tau_ps (1 - chi_1^peak))).
      if (c > 0 && (*mean_cos)[c] == (*mean_cos)[c - 1]) {
        b.tau_ps[c] = b.tau_ps[c - 1];
        continue;
      }
      b.tau_ps[c] =
          one_minus_chi1 > 0.0
              ? std::min(PhaseSplit::kTauMax, -std::log(std::max((*mean_cos)[c], 1e-12)) / one_minus_chi1)
              : 0.0;
      continue;
    }
    if (c > 0 && T_light[c] == T_light[c - 1] && T_wide[c] == T_wide[c - 1]) {
      b.tau_ps[c] = b.tau_ps[c - 1];
      b.T_wide[c] = b.T_wide[c - 1];
      continue;
    }
    // eq. D8: the straight beam's peak depth ln(T_wide / T_light), and optionally eq. D5.
    b.tau_ps[c] =
        T_light[c] > 1e-30 ? std::max(0.0, std::log(b.T_wide[c] / T_light[c])) : PhaseSplit::kTauMax;
    if (!traced && lengthening && b.T_wide[c] > 0.0)
      b.T_wide[c] *= path_lengthening(theta2 * b.tau_ps[c], -std::log(b.T_wide[c]));
  }
  // eq. D9: the traced beam's loss R (its lengthened paths included: no eq. D5), bounded (header).
  if (traced)
    for (int c = 0; c < 3; ++c) b.T_wide[c] = std::min(b.T_wide[c] * R[c], kMaxPeakTransmittance);
  return b;
}

Rgb first_wide_scatter(const Rgb& E, double f, const PhaseSplit& split, const PhaseSplit::Angle& a,
                       const Rgb& tau_p, const Rgb& tau_ps, const Rgb& T_wide) {
  // eq. D7, first term: light- and camera-side peak depths add (eq. D4).
  // One table lookup per distinct depth (grey media: one for the three channels).
  Rgb L;
  double tau_prev = 0.0, eff = 0.0;
  for (int c = 0; c < 3; ++c) {
    const double tau = tau_p[c] + tau_ps[c];
    if (c == 0 || tau != tau_prev) eff = split.wide_eff(tau, a), tau_prev = tau;
    L[c] = E[c] * (1.0 - f) * eff * T_wide[c];
  }
  return L;
}

Rgb first_wide_scatter(const Rgb& E, double f, const PhaseSplit& split, double mu, const Rgb& tau_p,
                       const Rgb& tau_ps, const Rgb& T_wide) {
  return first_wide_scatter(E, f, split, PhaseSplit::angle(mu), tau_p, tau_ps, T_wide);
}

Rgb forward_peak(const Rgb& E, double f, const PhaseSplit& split, const PhaseSplit::Angle& a, const Rgb& tau,
                 const Rgb& T) {
  // eq. D7, second term (or D7b for beer_lambert).
  Rgb L;
  double tau_prev = 0.0, eff = 0.0;
  for (int c = 0; c < 3; ++c) {
    if (c == 0 || tau[c] != tau_prev) eff = split.peak_eff(tau[c], a), tau_prev = tau[c];
    L[c] = E[c] * f * eff * T[c];
  }
  return L;
}

Rgb forward_peak(const Rgb& E, double f, const PhaseSplit& split, double mu, const Rgb& tau, const Rgb& T) {
  return forward_peak(E, f, split, PhaseSplit::angle(mu), tau, T);
}

Rgb light_side_scatter(const Rgb& E, double f, const PhaseSplit& split, double mu, const Rgb& tau_ps,
                       const Rgb& T_wide) {
  // eq. D11.
  Rgb L;
  const PhaseSplit::Angle a = PhaseSplit::angle(mu);
  for (int c = 0; c < 3; ++c)
    L[c] = E[c] * T_wide[c] * ((1.0 - f) * split.wide_eff(tau_ps[c], a) + f * split.peak_eff(tau_ps[c], a));
  return L;
}

namespace {
double moment(const std::vector<double>& m, int l, double fallback) {
  return int(m.size()) > l ? m[l] : fallback;
}
}  // namespace

std::array<Rgb, kShMaxBands> blurred_wide_moments(const PhaseSplit& split, const Rgb& tau_p, int bands) {
  // eq. D12 with eq. D3's camera-side blur of the wide part.
  const std::vector<double>& chi_w = split.wide_moments();
  const std::vector<double>& chi_p = split.peak_moments();
  std::array<Rgb, kShMaxBands> chi;
  chi.fill(Rgb(0.0));  // (Rgb, an Imath vector, is not zeroed by {}): l >= bands read as 0
  for (int l = 0; l < bands; ++l) {
    const double one_minus_chi = 1.0 - moment(chi_p, l, 1.0);
    const Rgb e =
        exp_channels(Rgb(-tau_p[0] * one_minus_chi, -tau_p[1] * one_minus_chi, -tau_p[2] * one_minus_chi));
    for (int c = 0; c < 3; ++c) chi[l][c] = moment(chi_w, l, 0.0) * e[c];
  }
  return chi;
}

std::array<Rgb, kShMaxBands> whole_phase_moments(const PhaseSplit& split, double f, int bands) {
  // eq. D12 with eq. D1's moments (chi_l of P itself).
  const std::vector<double>& chi_w = split.wide_moments();
  const std::vector<double>& chi_p = split.peak_moments();
  std::array<Rgb, kShMaxBands> chi;
  chi.fill(Rgb(0.0));  // (Rgb, an Imath vector, is not zeroed by {}): l >= bands read as 0
  for (int l = 0; l < bands; ++l)
    for (int c = 0; c < 3; ++c) chi[l][c] = f * moment(chi_p, l, 1.0) + (1.0 - f) * moment(chi_w, l, 0.0);
  return chi;
}

}  // namespace nimbus
