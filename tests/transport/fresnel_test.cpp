// The Fresnel surface of the slab lidar (src/transport/fresnel.h, lidar.h with fresnel = true): the
// reflectance against the angle forms of the Fresnel equations, Brewster, total internal reflection and
// reciprocity (R + T = 1 both ways); the refracted path's Snell law, its ray-tube spread against finite
// differences, the n^2 law and the Snell window; the Monte Carlo through the surface against the
// single-scatter equation with (h + n d)^2; n = 1 as the matched slab; causality; bad settings.
#include "transport/fresnel.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/math.h"
#include "nimbus/error.h"
#include "transport/lidar.h"

namespace nimbus {
namespace {

// Unpolarised reflectance from the sine and tangent forms (Born & Wolf), n_i = 1 -> n_t = eta.
double fresnel_by_angles(double theta_i, double eta) {
  const double theta_t = std::asin(std::sin(theta_i) / eta);
  const double rs = std::sin(theta_i - theta_t) / std::sin(theta_i + theta_t);
  const double rp = std::tan(theta_i - theta_t) / std::tan(theta_i + theta_t);
  return 0.5 * (rs * rs + rp * rp);
}

TEST(Fresnel, ReflectanceAgainstAngleFormsAndKnownPoints) {
  for (double n : {1.33, 1.5}) {
    EXPECT_NEAR(fresnel_reflectance(1.0, n), std::pow((n - 1) / (n + 1), 2), 1e-15);
    for (double th = 0.05; th < 1.55; th += 0.1)
      EXPECT_NEAR(fresnel_reflectance(std::cos(th), n), fresnel_by_angles(th, n), 1e-12);
    // Brewster: R_p = 0, so R = R_s / 2 = (cos 2 theta_B)^2 / 2.
    const double tb = std::atan(n);
    EXPECT_NEAR(fresnel_reflectance(std::cos(tb), n), 0.5 * std::pow(std::cos(2.0 * tb), 2), 1e-12);
    // From inside: total reflection beyond the critical angle, and the same R along the reversed ray.
    const double tc = std::asin(1.0 / n);
    EXPECT_EQ(fresnel_reflectance(std::cos(tc + 1e-6), 1.0 / n), 1.0);
    for (double th = 0.05; th < tc; th += 0.05) {
      const double ta = std::asin(n * std::sin(th));
      EXPECT_NEAR(fresnel_reflectance(std::cos(th), 1.0 / n), fresnel_reflectance(std::cos(ta), n), 1e-12);
    }
  }
}

TEST(Fresnel, RefractedPathSpreadSnellWindowAndNSquaredLaw) {
  const double n = 1.34, h = 0.7, d = 1.3;
  for (double rho : {0.0, 0.2, 1.0, 3.0}) {
    const RefractedPath p = refracted_path(h, d, rho, n);
    const double sin_w = std::sqrt(1 - p.cos_w * p.cos_w), sin_a = std::sqrt(1 - p.cos_a * p.cos_a);
    EXPECT_NEAR(n * sin_w, sin_a, 1e-10) << rho;
    EXPECT_NEAR(h * std::tan(std::acos(p.cos_w)) + d * std::tan(std::acos(p.cos_a)), rho, 1e-10);
    // dA / dOmega by finite differences of rho(theta_w) = h tan theta_w + d tan theta_a.
    const double tw = std::acos(p.cos_w), e = 1e-5;
    auto rho_of = [&](double t) { return h * std::tan(t) + d * std::tan(std::asin(n * std::sin(t))); };
    if (rho > 0.0) {
      const double spread = rho * (rho_of(tw + e) - rho_of(tw - e)) / (2 * e) / std::sin(tw);
      EXPECT_NEAR(p.spread, spread, 1e-6 * spread) << rho;
    }
  }
  // On the vertical: (h + n d)^2; just below the surface n^2 d^2, against d^2 in air: the n^2 law of
  // radiance (the same flux through a solid angle n^2 times smaller below).
  EXPECT_NEAR(refracted_path(h, d, 0.0, n).spread, std::pow(h + n * d, 2), 1e-9);
  EXPECT_NEAR(refracted_path(1e-9, d, 0.0, n).spread / (d * d), n * n, 1e-6);
  // The Snell window: however far the point in the air, the water leg stays within the critical angle.
  EXPECT_NEAR(std::sqrt(1 - std::pow(refracted_path(h, d, 1e6, n).cos_w, 2)), 1.0 / n, 1e-5);
}

LidarSettings surface_settings() {
  LidarSettings s;
  s.sigma_s = 0.1;
  s.sigma_a = 0.02;
  s.phase = HgPhase{0.9};
  s.thickness = 2.0;
  s.distance = 0.5;
  s.n = 1.33;
  s.fresnel = true;
  s.fov = 0.002;
  for (int i = 0; i <= 8; ++i) s.time_edges.push_back(1.0 + 0.6 * i);  // depths 0 .. 1.8
  s.photons = 400000;
  s.seed = 5;
  return s;
}

TEST(Fresnel, LidarMcThroughTheSurfaceIsTheSingleScatterEquation) {
  const LidarSettings s = surface_settings();
  const LidarMcResult mc = run_lidar_mc(s);
  const std::vector<double> single = lidar_single_scatter(s);
  int powerful = 0;
  for (size_t i = 0; i < single.size(); ++i) {
    const Estimate& m = mc.received.bins[i];
    // Double scattering through the HG peak adds up to ~3 % at the deepest bins (as without a surface).
    EXPECT_NEAR(m.value, single[i], 5.0 * m.err + 0.03 * single[i]) << i;
    powerful += m.err < 0.03 * single[i];
  }
  EXPECT_GE(powerful, 6);
  EXPECT_EQ(mc.received.before.value, 0.0);  // nothing before 2 d (the surface return is its own row)
  // The surface return: R(0) / (pi r^2).
  LidarSettings disk = s;
  disk.r_rx = 0.1;
  EXPECT_NEAR(lidar_surface_return(disk), std::pow(0.33 / 2.33, 2) / (kPi * 0.01), 1e-12);
}

TEST(Fresnel, IndexOneIsTheMatchedSlab) {
  LidarSettings s = surface_settings();
  s.n = 1.0;
  s.sigma_s = 1.0;
  s.fov = 0.2;
  s.r_rx = 0.1;
  s.photons = 20000;
  const LidarMcResult f = run_lidar_mc(s);
  s.fresnel = false;
  const LidarMcResult m = run_lidar_mc(s);
  for (size_t i = 0; i < f.received.bins.size(); ++i)
    EXPECT_NEAR(f.received.bins[i].value, m.received.bins[i].value, 1e-9 * m.received.bins[i].value) << i;
  EXPECT_NEAR(f.analog.value, m.analog.value, 1e-12);
  const std::vector<double> a = lidar_single_scatter(s);
  s.fresnel = true;
  const std::vector<double> b = lidar_single_scatter(s);
  for (size_t i = 0; i < a.size(); ++i) EXPECT_NEAR(b[i], a[i], 1e-6 * a[i]) << i;
}

TEST(Fresnel, RejectsWhatItCannotDo) {
  LidarSettings s = surface_settings();
  EXPECT_THROW(lidar_mfs(s), Error);
  s.distance = 0.0;
  EXPECT_THROW(run_lidar_mc(s), Error);
  EXPECT_THROW(lidar_single_scatter(s), Error);
}

}  // namespace
}  // namespace nimbus
