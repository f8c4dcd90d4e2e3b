// Slab Monte Carlo against independent solutions: Chandrasekhar's H-function for a semi-infinite
// isotropic medium, and van de Hulst's tabulated slab (the MCML paper's first check).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/math.h"
#include "transport/photon_mc.h"

namespace nimbus {
namespace {

// Gauss-Legendre nodes and weights on [0, 1].
void gauss_legendre01(int n, std::vector<double>& x, std::vector<double>& w) {
  x.resize(n);
  w.resize(n);
  for (int i = 0; i < n; ++i) {
    double t = std::cos(kPi * (i + 0.75) / (n + 0.5)), dp = 1.0;
    for (int it = 0; it < 100; ++it) {
      double p0 = 1.0, p1 = t;
      for (int k = 2; k <= n; ++k) {
        const double p2 = ((2 * k - 1) * t * p1 - (k - 1) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      dp = n * (t * p1 - p0) / (t * t - 1.0);
      const double dt = p1 / dp;
      t -= dt;
      if (std::abs(dt) < 1e-15) break;
    }
    x[i] = 0.5 * (1.0 + t);
    w[i] = 1.0 / ((1.0 - t * t) * dp * dp);  // 2 / ((1 - t^2) P'^2), halved for [0, 1]
  }
}

// Plane albedo of a semi-infinite isotropic medium for normal incidence: 1 - H(1) sqrt(1 - omega),
// with 1 / H(mu) = sqrt(1 - omega) + (omega / 2) int_0^1 mu' H(mu') / (mu + mu') dmu'.
double semi_infinite_isotropic_albedo(double omega) {
  std::vector<double> x, w;
  gauss_legendre01(96, x, w);
  std::vector<double> H(x.size(), 1.0);
  auto h_at = [&](double mu) {
    double s = 0.0;
    for (size_t j = 0; j < x.size(); ++j) s += w[j] * x[j] * H[j] / (mu + x[j]);
    return 1.0 / (std::sqrt(1.0 - omega) + 0.5 * omega * s);
  };
  for (int it = 0; it < 2000; ++it) {
    std::vector<double> next(x.size());
    for (size_t i = 0; i < x.size(); ++i) next[i] = h_at(x[i]);
    H = next;
  }
  return 1.0 - h_at(1.0) * std::sqrt(1.0 - omega);
}

TEST(PhotonMcSlow, SemiInfiniteIsotropicMatchesHFunction) {
  const double omega = 0.9;
  const double expected = semi_infinite_isotropic_albedo(omega);
  EXPECT_NEAR(expected, 0.41495,
              1e-4);  // H(1) = 1.8501 (the H integral identity checked in the notes of this test)
  PhotonMcSettings s;
  s.sigma_s = omega;
  s.sigma_a = 1.0 - omega;
  s.phase = IsotropicPhase{};
  s.thickness = 200.0;  // semi-infinite for all practical purposes
  s.photons = 200000;
  s.batches = 20;
  const PhotonMcResult r = run_photon_mc(s);
  EXPECT_NEAR(r.diffuse_reflectance.value, expected, 5.0 * r.diffuse_reflectance.err + 2e-4);
  EXPECT_LT(r.transmittance.value, 1e-12);
}

TEST(PhotonMcSlow, VanDeHulstSlabTable) {
  // mu_a = 10, mu_s = 90 /cm, g = 0.75, d = 0.02 cm, n = 1: Rd = 0.09739, Tt = 0.66096 (van de Hulst 1980,
  // as tabulated in Wang, Jacques & Zheng 1995).  Tt includes the unscattered exp(-2).
  PhotonMcSettings s;
  s.sigma_s = 90.0;
  s.sigma_a = 10.0;
  s.phase = HgPhase{0.75};
  s.thickness = 0.02;
  s.photons = 200000;
  s.batches = 20;
  const PhotonMcResult r = run_photon_mc(s);
  EXPECT_NEAR(r.diffuse_reflectance.value, 0.09739, 5.0 * r.diffuse_reflectance.err + 3e-4);
  EXPECT_NEAR(r.transmittance.value, 0.66096, 5.0 * r.transmittance.err + 3e-4);
  EXPECT_NEAR(r.unscattered_transmittance.value, std::exp(-2.0), 5.0 * r.unscattered_transmittance.err);
  EXPECT_EQ(r.specular.value, 0.0);
}

// Giovanelli's semi-infinite isotropic medium (albedo 0.9) with a mismatched boundary, n = 1.5: total
// reflection (specular 0.04 included) 0.2600, as quoted in the MCML checks (Prahl et al. 1989; Wang,
// Jacques & Zheng 1995).  (With n = 1 the exact value is the H-function's 0.4149, tested above.)
TEST(PhotonMcSlow, SemiInfiniteMismatchedBoundaryGiovanelli) {
  PhotonMcSettings s;
  s.sigma_s = 90.0;
  s.sigma_a = 10.0;
  s.phase = IsotropicPhase{};
  s.thickness = 2.0;  // 200 mean free paths
  s.n = 1.5;
  s.photons = 200000;
  s.batches = 20;
  const PhotonMcResult r = run_photon_mc(s);
  EXPECT_NEAR(r.specular.value, 0.04, 1e-12);
  EXPECT_NEAR(r.specular.value + r.diffuse_reflectance.value, 0.2600, 5.0 * r.diffuse_reflectance.err + 5e-4);
  EXPECT_NEAR(r.specular.value + r.diffuse_reflectance.value + r.transmittance.value + r.absorbed.value, 1.0,
              1e-4);
}

}  // namespace
}  // namespace nimbus
