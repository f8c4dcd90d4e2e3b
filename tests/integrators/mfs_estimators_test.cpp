// The `mfs` estimators alone (integrators/mfs_estimators.h): each checked against the equation of
// docs/derivations.md it cites, without a scene.
#include "integrators/mfs_estimators.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/rng.h"
#include "media/phase.h"
#include "transport/small_angle.h"

namespace nimbus {
namespace {

TEST(MfsEstimators, PathLengtheningIsOneOverCosh) {  // eq. D5
  EXPECT_EQ(path_lengthening(0.0, 5.0), 1.0);
  EXPECT_EQ(path_lengthening(-1.0, 5.0), 1.0);  // clamped at 0
  for (double theta : {0.01, 0.3, 2.0})
    for (double tau : {0.1, 1.0, 30.0})
      EXPECT_NEAR(path_lengthening(theta, tau), 1.0 / std::cosh(std::sqrt(theta * tau)), 1e-14);
}

TEST(MfsEstimators, ExtinctionSplitSumsTheMedia) {  // eq. D2
  MediumPoint mp;
  mp.count = 2;
  mp.sigma_s_i[0] = Rgb(1.0, 2.0, 3.0);
  mp.sigma_s_i[1] = Rgb(0.5);
  mp.sigma_s = mp.sigma_s_i[0] + mp.sigma_s_i[1];
  mp.sigma_a = Rgb(0.25);
  const MfsExtinction k = mfs_extinction(mp, {0.8, 0.5}, {0.01, 0.1});
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(k.sigma_peak[c], 0.8 * mp.sigma_s_i[0][c] + 0.25, 1e-12);
    EXPECT_NEAR(k.sigma_theta[c], 0.008 * mp.sigma_s_i[0][c] + 0.025, 1e-12);
    EXPECT_NEAR(k.sigma_red[c], 0.2 * mp.sigma_s_i[0][c] + 0.5, 1e-12);
  }
}

// eq. D16 on a path through a uniform medium that begins at z0 (empty before it): the offset and the
// deflection accumulate var(u) = a L^3 / 3, cov = a L^2 / 2 and var(delta) = a L over the L crossed, so
// E[delta | u] = 3 u / (2 L) and a quarter of the deflection's variance is left; without any peak depth
// the direction is the ray's.
TEST(MfsEstimators, SurvivorDirectionOnAUniformPath) {
  const Vec3 d(0.0, 0.0, 1.0), u(0.02, -0.01, 0.0);
  double residual = -1.0;
  EXPECT_EQ(survivor_direction(CameraPath{}, 3.0, d, u, &residual), d);
  EXPECT_EQ(residual, 1.0);
  MfsExtinction k{Rgb(2.0), Rgb(1.5), Rgb(0.03), Rgb(0.5)};
  CameraPath cam;
  const double z0 = 1.25, dt = 0.001;
  int n = 0;
  for (double t = z0 + 0.5 * dt; n < 2000; t += dt, ++n) cam.advance(k, t, dt, 0.5);
  const double L = n * dt;
  const Vec3 got = survivor_direction(cam, z0 + L, d, u, &residual);
  const Vec3 want = normalize(d + u * (1.5 / L));
  EXPECT_NEAR(residual, 0.25, 1e-5);
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(got[a], want[a], 1e-7) << a;
  EXPECT_NEAR(got.length(), 1.0, 1e-12);
}

// camera_tilt's footprint offsets (eq. D16): any 16 consecutive offsets of one probe visit every radius
// stratum once, so their mean square length is the footprint's 2 sigma^2 exactly, and each is
// perpendicular to d; over random starts, one step's offset has mean 0 and variance sigma^2 along each
// axis of the plane (within 4 standard errors of the sample).
// eq. D17: for a jointly Gaussian offset u and deflection delta (per component: var v, cov c, var m0) and a
// source exp(a u) g(delta), the source weighted by exp(a u) reads g as if delta's mean were moved by a c:
// E[exp(a u) g(delta)] / E[exp(a u)] = E[g(delta + a c)], for any g (here a lopsided bump), by quadrature
// over the two standard normals. And gradient_tilted moves d towards wi by that angle: atan(k sin theta)
// in the plane of d and wi, nothing for wi along d.
TEST(MfsEstimators, GradientTiltIsTheGaussianShiftOfTheDeflection) {
  const double v = 0.04, c = 0.05, m0 = 0.3, a = 2.9;
  const auto g = [](double x) { return 1.0 / (1.0 + (x - 0.3) * (x - 0.3)) + 0.2 * x * x * x; };
  double w_sum = 0.0, wg = 0.0, shifted = 0.0, norm = 0.0;
  const int n = 801;
  const double h = 16.0 / (n - 1);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const double z1 = -8.0 + i * h, z2 = -8.0 + j * h;
      const double p = std::exp(-0.5 * (z1 * z1 + z2 * z2));
      const double u = std::sqrt(v) * z1, delta = c / std::sqrt(v) * z1 + std::sqrt(m0 - c * c / v) * z2;
      w_sum += p * std::exp(a * u);
      wg += p * std::exp(a * u) * g(delta);
      shifted += p * g(delta + a * c);
      norm += p;
    }
  EXPECT_NEAR(wg / w_sum, shifted / norm, 1e-9 * std::abs(shifted / norm));
  EXPECT_GT(std::abs(wg / w_sum -
                     [&] {  // (and the weight matters: unweighted, g reads otherwise)
                       double s = 0.0;
                       for (int i = 0; i < n; ++i)
                         for (int j = 0; j < n; ++j) {
                           const double z1 = -8.0 + i * h, z2 = -8.0 + j * h;
                           s += std::exp(-0.5 * (z1 * z1 + z2 * z2)) *
                                g(c / std::sqrt(v) * z1 + std::sqrt(m0 - c * c / v) * z2);
                         }
                       return s / norm;
                     }()),
            0.01);
  const Vec3 d(0.0, 0.0, 1.0), wi = normalize(Vec3(1.0, 0.0, 1.0));  // 45 degrees
  const Vec3 t = gradient_tilted(d, wi, 0.2);
  EXPECT_NEAR(std::atan2(t.x, t.z), std::atan(0.2 * std::sin(kPi / 4.0)), 1e-12);
  EXPECT_EQ(t.y, 0.0);
  EXPECT_NEAR(t.length(), 1.0, 1e-12);
  const Vec3 along = gradient_tilted(d, d, 0.2);
  EXPECT_NEAR((along - d).length(), 0.0, 1e-15);
}

// camera_shift's tilt cut at the medium's surface (eq. D17b): k times the mean offset under the weight
// exp(a u) on u < D, by quadrature, over the uncut mean a s^2; k itself far from the surface, and 0 where
// the cut mean turns away from the light.
TEST(MfsEstimators, TruncatedGradientTiltIsTheCutWeightsMeanOffset) {
  const double k = 0.7, a = 3.0, s = 0.2;
  for (const double D : {0.02, 0.1, 0.2, 0.4, 1.0}) {
    double w = 0.0, wu = 0.0;
    const int n = 200001;
    const double lo = -12.0 * s, h = (D - lo) / (n - 1);
    for (int i = 0; i < n; ++i) {  // the trapezoidal rule over [lo, D]
      const double u = lo + i * h,
                   p = std::exp(-0.5 * u * u / (s * s) + a * u) * (i == 0 || i == n - 1 ? 0.5 : 1.0);
      w += p;
      wu += p * u;
    }
    const double expected = k * std::max(0.0, (wu / w) / (a * s * s));
    EXPECT_NEAR(truncated_gradient_tilt(k, a, s, D), expected, 1e-6) << D;
  }
  EXPECT_NEAR(truncated_gradient_tilt(k, a, s, 20.0), k, 1e-12);
  EXPECT_EQ(truncated_gradient_tilt(k, a, s, std::numeric_limits<double>::infinity()), k);
  EXPECT_EQ(truncated_gradient_tilt(k, a, s, 0.0), 0.0);  // the cut mean is below 0
  EXPECT_LT(truncated_gradient_tilt(k, a, s, 0.2), 0.8 * k);
}

TEST(MfsEstimators, FootprintProbeHasTheFootprintsMoments) {
  const Vec3 d = normalize(Vec3(0.3, -0.5, 0.8));
  const double sigma = 0.5;
  FootprintProbe probe(d, 0.37, 0.81);
  for (int round = 0; round < 3; ++round) {
    double m2 = 0.0;
    for (int k = 0; k < FootprintProbe::kStrata; ++k) {
      const Vec3 u = probe.next(sigma);
      EXPECT_NEAR(dot(u, d), 0.0, 1e-12);
      m2 += dot(u, u) / FootprintProbe::kStrata;
    }
    EXPECT_NEAR(m2, 2.0 * sigma * sigma, 1e-12) << round;
  }
  const Frame fr(d);
  Rng rng(7, 0);
  const int n = 40000;
  double sx = 0.0, sy = 0.0, sxx = 0.0, syy = 0.0, sx4 = 0.0;
  for (int i = 0; i < n; ++i) {
    const double u1 = rng.uniform(), u2 = rng.uniform();
    FootprintProbe p(d, u1, u2);
    Vec3 u;
    for (int k = 0; k < 4; ++k) u = p.next(sigma);  // the fourth step's offset
    const double x = dot(u, fr.s), y = dot(u, fr.t);
    sx += x, sy += y, sxx += x * x, syy += y * y, sx4 += x * x * x * x;
  }
  const double var_x = sxx / n, se_mean = std::sqrt(var_x / n);
  const double se_var = std::sqrt((sx4 / n - var_x * var_x) / n);
  EXPECT_NEAR(sx / n, 0.0, 4.0 * se_mean);
  EXPECT_NEAR(sy / n, 0.0, 4.0 * se_mean);
  EXPECT_NEAR(var_x, sigma * sigma, 4.0 * se_var);
  EXPECT_NEAR(syy / n, sigma * sigma, 4.0 * se_var);
}

TEST(MfsEstimators, CameraPathAccumulatesDepthsAndSpread) {  // eqs. D2, D10
  MfsExtinction k{Rgb(2.0), Rgb(1.5), Rgb(0.03), Rgb(0.5)};
  CameraPath cam;
  const double dt = 0.01;
  int n = 0;
  for (double t = 0.5 * dt; n < 300; t += dt, ++n) cam.advance(k, t, dt, 0.5);
  const double z = n * dt;
  EXPECT_NEAR(cam.T_full[0], std::exp(-2.0 * z), 1e-12);
  EXPECT_NEAR(cam.T_red[1], std::exp(-0.5 * z), 1e-12);
  EXPECT_NEAR(cam.tau_p[2], 1.5 * z, 1e-12);
  EXPECT_NEAR(cam.theta_p[0], 0.03 * z, 1e-12);
  // Uniform sigma_theta: var(t) = sigma_theta int_0^z (t - s)^2 ds; at t = z, sigma_theta z^3 / 3.
  EXPECT_NEAR(cam.lateral_spread(z), std::sqrt(0.03 * z * z * z / 3.0),
              1e-4 * std::sqrt(0.03 * z * z * z / 3.0));
  // The sample point half a step further, and the light-side choice of transmittance.
  const CameraPoint y = cam.at(k, 0.5, dt, false, false), yl = cam.at(k, 0.5, dt, true, false);
  EXPECT_NEAR(y.T_cam[0], std::exp(-0.5 * (z + 0.5 * dt)), 1e-12);
  EXPECT_NEAR(y.tau_p[0], 1.5 * (z + 0.5 * dt), 1e-12);
  EXPECT_EQ(yl.T_cam, yl.T_full);
  const CameraPoint yc = cam.at(k, 0.5, dt, false, true);  // with eq. D5
  EXPECT_NEAR(yc.T_cam[0], y.T_cam[0] / std::cosh(std::sqrt(0.03 * (z + 0.5 * dt) * 0.5 * (z + 0.5 * dt))),
              1e-12);
}

TEST(MfsEstimators, PeakOnlyBeamDepths) {  // eqs. D8, D9
  const std::vector<double> chi_p = {1.0, 0.9, 0.75};
  const Rgb T_light(0.1, 0.2, 0.3), T_wide(0.5, 0.4, 0.3);
  const LightBeam s = peak_only_beam(T_light, T_wide, false, Rgb(1.0), nullptr, chi_p, 0.05, false);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(s.tau_ps[c], std::log(T_wide[c] / T_light[c]), 1e-15);
  EXPECT_EQ(s.T_wide, T_wide);
  const LightBeam sl = peak_only_beam(T_light, T_wide, false, Rgb(1.0), nullptr, chi_p, 0.05, true);
  EXPECT_NEAR(sl.T_wide[0], T_wide[0] * path_lengthening(0.05 * s.tau_ps[0], -std::log(T_wide[0])), 1e-15);
  // Traced: R multiplies T_wide; the mean cosine of a beam after tau is exp(-tau (1 - chi_1)) (eq. D3).
  const Rgb tau(0.0, 1.0, 7.0);
  const Rgb mean_cos(std::exp(-tau[0] * 0.1), std::exp(-tau[1] * 0.1), std::exp(-tau[2] * 0.1));
  const LightBeam b = peak_only_beam(T_light, T_wide, true, Rgb(0.5), &mean_cos, chi_p, 0.05, true);
  // Traced without the mean cosine (beam_spread "straight"): R multiplies T_wide, the spread is D8's.
  const Rgb R(0.5, 0.7, 0.9);
  const LightBeam st = peak_only_beam(T_light, T_wide, true, R, nullptr, chi_p, 0.05, true);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(b.tau_ps[c], tau[c], 1e-12);
    EXPECT_DOUBLE_EQ(b.T_wide[c], 0.5 * T_wide[c]);
    EXPECT_EQ(st.tau_ps[c], s.tau_ps[c]);
    EXPECT_DOUBLE_EQ(st.T_wide[c], R[c] * T_wide[c]);
  }
}

// The traced beam's T_wide R is bounded by kMaxPeakTransmittance (a nearly empty straight tally gave R ~
// 10^6 in the smoke plume), per channel; below the bound R multiplies as before, bit for bit.
TEST(MfsEstimators, TracedPeakTransmittanceIsBounded) {
  const std::vector<double> chi_p = {1.0, 0.9, 0.75};
  const Rgb T_light(0.01, 0.2, 0.3), T_wide(0.05, 0.4, 0.9);
  const Rgb R(2.0e6, 1.3, 2.0);  // channel 0: a failed ratio; 1: lengthened paths; 2: 1.8 > the bound
  const LightBeam b = peak_only_beam(T_light, T_wide, true, R, nullptr, chi_p, 0.05, false);
  EXPECT_EQ(b.T_wide[0], kMaxPeakTransmittance);
  EXPECT_EQ(b.T_wide[1], T_wide[1] * R[1]);
  EXPECT_EQ(b.T_wide[2], std::min(T_wide[2] * R[2], kMaxPeakTransmittance));
  EXPECT_GT(T_wide[2] * R[2], 1.0);  // channel 2 is above 1 and kept: the bound is not at 1
  EXPECT_LT(kMaxPeakTransmittance, 10.0);
}

TEST(MfsEstimators, PeakDepthsAddInTheMoments) {  // eqs. D3, D4, D12
  const Phase phase = HgPhase{0.85};
  const PhaseSplit split(phase, auto_peak_fraction(phase));
  const auto a = blurred_wide_moments(split, Rgb(0.7), 3), b = blurred_wide_moments(split, Rgb(1.8), 3);
  const auto ab = blurred_wide_moments(split, Rgb(2.5), 3), none = blurred_wide_moments(split, Rgb(0.0), 3);
  for (int l = 0; l < 3; ++l) EXPECT_NEAR(ab[l][0] * none[l][0], a[l][0] * b[l][0], 1e-12) << l;
  EXPECT_NEAR(none[0][1], 1.0, 1e-6);
  // The whole phase function's moments: chi_1 = g.
  const auto whole = whole_phase_moments(split, split.f(), 3);
  EXPECT_NEAR(whole[0][0], 1.0, 1e-9);
  EXPECT_NEAR(whole[1][2], 0.85, 2e-3);
}

TEST(MfsEstimators, EstimatorsAreTheirFormulas) {  // eqs. D7, D7b, D11
  const Phase phase = HgPhase{0.9};
  const PhaseSplit split(phase, 0.6);
  const double f = split.f(), mu = 0.8;
  const Rgb E(1.0, 2.0, 0.5), tau_p(0.5, 1.0, 3.0), tau_ps(0.2, 0.0, 4.0), T(0.3, 0.6, 0.9);
  const Rgb wide = first_wide_scatter(E, f, split, mu, tau_p, tau_ps, T);
  const Rgb peak = forward_peak(E, f, split, mu, tau_ps, T);
  const Rgb light = light_side_scatter(E, f, split, mu, tau_ps, T);
  for (int c = 0; c < 3; ++c) {
    EXPECT_DOUBLE_EQ(wide[c], E[c] * (1.0 - f) * split.wide_eff(tau_p[c] + tau_ps[c], mu) * T[c]);
    EXPECT_DOUBLE_EQ(peak[c], E[c] * f * split.peak_eff(tau_ps[c], mu) * T[c]);
    EXPECT_NEAR(light[c], (1.0 - f) * E[c] * split.wide_eff(tau_ps[c], mu) * T[c] + peak[c],
                1e-12 * light[c]);
  }
  // No spread on either side: the light side's scatter is the phase function itself.
  const Rgb at0 = light_side_scatter(Rgb(1.0), f, split, mu, Rgb(0.0), Rgb(1.0));
  EXPECT_NEAR(at0[0], phase_eval(phase, mu), 0.03 * phase_eval(phase, mu) + 1e-3);
}

TEST(MfsEstimators, LateralOffsetIsAPerpendicularGaussian) {  // eq. D14
  const Vec3 d = normalize(Vec3(0.3, -1.0, 0.4));
  EXPECT_EQ(lateral_offset(d, 0.0, 0.3, 0.7), Vec3(0.0));
  const Frame fr(d);
  const double sigma = 0.3;
  const int n = 40000;
  double ss = 0.0, tt = 0.0, st = 0.0, ms = 0.0, mt = 0.0, inside = 0.0;
  Rng rng(11, 3);
  for (int i = 0; i < n; ++i) {
    const Vec3 v = lateral_offset(d, sigma, rng.uniform(), rng.uniform());
    EXPECT_NEAR(dot(v, d), 0.0, 1e-12);
    const double a = dot(v, fr.s), b = dot(v, fr.t);
    ms += a, mt += b, ss += a * a, tt += b * b, st += a * b;
    inside += (a * a + b * b < sigma * sigma) ? 1.0 : 0.0;
  }
  // Per-component variance sigma^2, uncorrelated, zero mean (5 standard errors); the 2-D Gaussian puts
  // 1 - exp(-1/2) of its weight within sigma of the axis.
  const double v = sigma * sigma, se_v = v * std::sqrt(2.0 / n), se_m = sigma / std::sqrt(double(n));
  EXPECT_NEAR(ss / n, v, 5 * se_v);
  EXPECT_NEAR(tt / n, v, 5 * se_v);
  EXPECT_NEAR(st / n, 0.0, 5 * v / std::sqrt(double(n)));
  EXPECT_NEAR(ms / n, 0.0, 5 * se_m);
  EXPECT_NEAR(mt / n, 0.0, 5 * se_m);
  const double p_in = 1.0 - std::exp(-0.5);
  EXPECT_NEAR(inside / n, p_in, 5 * std::sqrt(p_in * (1 - p_in) / n));
}

TEST(MfsEstimators, CameraFluenceConservesTheBeamsLight) {  // eq. D19
  // A homogeneous medium: sigma_red = 0.3, drift rate kappa = 0.02. The fluence factor is
  // e^(kappa z) exp(-sigma_red ((e^(kappa z) - 1) / kappa - z)), and in an infinite medium every bit of the
  // beam's flux is lost to sigma_red somewhere: int sigma_red T_cam dz = 1, as for the straight beam.
  const double sr = 0.3, kappa = 0.02, dt = 0.01;
  MfsExtinction k{Rgb(1.0), Rgb(0.7), Rgb(0.02), Rgb(sr), Rgb(kappa)};
  CameraPath cam;
  double total = 0.0;
  for (int n = 0; n < 8000; ++n) {
    const double z = (n + 0.5) * dt;
    const CameraPoint y = cam.at(k, 0.5, dt, false, false, true);
    const double expected =
        std::exp(-sr * z) * std::exp(kappa * z) * std::exp(-sr * ((std::exp(kappa * z) - 1.0) / kappa - z));
    if (n % 500 == 0) EXPECT_NEAR(y.T_cam[1] / expected, 1.0, 1e-6) << z;
    total += sr * y.T_cam[0] * dt;
    cam.advance(k, z, dt, 0.5);
  }
  EXPECT_NEAR(total, 1.0, 1e-4);
  // Without the drift the factor is 1: the plain T_red.
  MfsExtinction k0{Rgb(1.0), Rgb(0.7), Rgb(0.02), Rgb(sr)};
  CameraPath cam0;
  for (int n = 0; n < 100; ++n) cam0.advance(k0, (n + 0.5) * dt, dt, 0.5);
  EXPECT_EQ(cam0.at(k0, 0.5, dt, false, false, true).T_cam, cam0.at(k0, 0.5, dt, false, false, false).T_cam);
}

// The light that a source exp(kappa z) sends out of a half-space (sigma_t = 1, albedo 0.99, HG 0.85 with its
// auto split) along the normal, carried by the peak alone: exactly, by photons walked from the surface
// inwards (flights at the peak rate, directions from P_peak, the reduced extinction a continuous loss; by
// reciprocity the camera-side beam), and by the march's T_cam with and without eq. D19.
struct HalfSpaceLight {
  double mc, mc_se, fluence, flux;
};
HalfSpaceLight half_space_light(double kappa) {
  const Phase phase = HgPhase{0.85};
  const PhaseSplit split(phase, auto_peak_fraction(phase));
  const double sp = 0.99 * split.f(), sr = 1.0 - sp;
  // Photons: per flight from z0 along mu, int_0^L exp(-sr s) exp(kappa (z0 + mu s)) ds in closed form.
  Rng rng(19, 0);
  const int n = 20000;
  double sum = 0.0, sum2 = 0.0;
  for (int i = 0; i < n; ++i) {
    Vec3 x(0.0), w(0.0, 0.0, 1.0);
    double weight = 1.0, total = 0.0;
    while (weight > 1e-5 && x.z >= 0.0) {
      const double L = -std::log(1.0 - rng.uniform()) / sp, a = sr - kappa * w.z;
      const double inside = w.z < 0.0 ? std::min(L, x.z / -w.z) : L;  // no source beyond the surface
      total += weight * std::exp(kappa * x.z) * -std::expm1(-a * inside) / a;
      x += w * L;
      weight *= std::exp(-sr * L);
      for (int tries = 0; tries < 10000; ++tries) {  // P_peak by rejection from P
        const Vec3 v = phase_sample(phase, w, rng.uniform(), rng.uniform());
        if (rng.uniform() >= split.wide_share(dot(v, w))) {
          w = v;
          break;
        }
      }
    }
    sum += total;
    sum2 += total * total;
  }
  HalfSpaceLight out{};
  out.mc = sum / n;
  out.mc_se = std::sqrt(std::max(0.0, sum2 / n - out.mc * out.mc) / n);
  // The march: the midpoint of each step (jitter 1/2).
  const std::vector<double> drift = {1.0 - split.peak_moments()[1]};
  MediumPoint mp;
  mp.count = 1;
  mp.sigma_s_i[0] = Rgb(0.99);
  mp.sigma_s = Rgb(0.99);
  mp.sigma_a = Rgb(0.01);
  const MfsExtinction k = mfs_extinction(mp, {split.f()}, {split.theta2()}, drift);
  CameraPath cam;
  const double dt = 0.01;
  for (int j = 0; j < 20000; ++j) {
    const double z = (j + 0.5) * dt;
    out.fluence += cam.at(k, 0.5, dt, false, false, true).T_cam[0] * std::exp(kappa * z) * dt;
    out.flux += cam.at(k, 0.5, dt, false, false, false).T_cam[0] * std::exp(kappa * z) * dt;
    cam.advance(k, z, dt, 0.5);
  }
  return out;
}

TEST(MfsEstimators, CameraFluenceMatchesPeakWalksInAHalfSpace) {  // eq. D19
  // A source growing inwards (a backlit medium seen from its exit face) sends out less than the straight
  // picture says, one falling inwards (front-lit) more; D19 must take at least 3/4 of the way to the walks.
  for (const double kappa : {0.1, -0.15}) {
    const HalfSpaceLight h = half_space_light(kappa);
    const double gap = h.mc - h.flux;
    EXPECT_GT(std::abs(gap), 6.0 * h.mc_se) << kappa;  // the flux misses it
    EXPECT_LT(std::abs(h.fluence - h.mc), 0.25 * std::abs(gap) + 3.0 * h.mc_se) << kappa;
    EXPECT_GT(gap * (kappa > 0.0 ? -1.0 : 1.0), 0.0) << kappa;
  }
}

}  // namespace
}  // namespace nimbus
