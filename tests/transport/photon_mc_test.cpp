// Photon Monte Carlo: Fresnel, unscattered light, energy balance, exact non-scattering slabs,
// determinism across thread counts.  Short runs; tolerances from the estimated standard errors.
#include "transport/photon_mc.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>

#include "core/math.h"
#include "nimbus/error.h"

namespace nimbus {
namespace {

TEST(Fresnel, NormalIncidenceTotalInternalReflectionAndReciprocity) {
  EXPECT_NEAR(fresnel_reflectance(1.0, 1.5, 1.0), 0.04, 1e-15);
  EXPECT_NEAR(fresnel_reflectance(1.33, 1.0, 1.0), std::pow(0.33 / 2.33, 2), 1e-15);
  EXPECT_EQ(fresnel_reflectance(1.0, 1.0, 0.3), 0.0);
  // Critical angle from 1.5 to 1: sin = 1/1.5.
  const double cos_c = std::sqrt(1.0 - 1.0 / 2.25);
  EXPECT_EQ(fresnel_reflectance(1.5, 1.0, cos_c - 1e-6), 1.0);
  EXPECT_LT(fresnel_reflectance(1.5, 1.0, cos_c + 1e-3), 1.0);
  EXPECT_NEAR(fresnel_reflectance(1.0, 1.5, 0.0), 1.0, 1e-12);  // grazing
  // Reciprocity: R(n1 -> n2, theta_i) = R(n2 -> n1, theta_t).
  for (double ci : {0.95, 0.7, 0.4, 0.1}) {
    double ct = 0.0;
    const double r12 = fresnel_reflectance(1.0, 1.4, ci, &ct);
    EXPECT_NEAR(fresnel_reflectance(1.4, 1.0, ct), r12, 1e-13);
  }
  // Brewster: rp = 0 at tan theta = n2/n1, so R = rs^2 / 2.
  const double tb = std::atan(1.5), ct = std::cos(std::asin(std::sin(tb) / 1.5));
  const double rs = (std::cos(tb) - 1.5 * ct) / (std::cos(tb) + 1.5 * ct);
  EXPECT_NEAR(fresnel_reflectance(1.0, 1.5, std::cos(tb)), 0.5 * rs * rs, 1e-13);
}

TEST(PhotonMc, UnscatteredLightFollowsBeerLambert) {
  PhotonMcSettings s;
  s.sigma_s = 1.0;
  s.sigma_a = 1.0 / 9.0;  // albedo 0.9
  s.phase = HgPhase{0.9};
  s.plane_depths = {0.5, 1.0, 2.0, 3.0};
  s.theta_edges = {0.0, 0.1, kPi};
  s.r_edges = {0.0, 1.0};
  s.photons = 20000;
  s.batches = 20;
  const PhotonMcResult r = run_photon_mc(s);
  for (const PlaneTally& t : r.planes) {
    const double expected = std::exp(-(s.sigma_s + s.sigma_a) * t.depth);
    EXPECT_NEAR(t.unscattered.value, expected, 5.0 * t.unscattered.err) << t.depth;
    EXPECT_GT(t.unscattered.err, 0.0);
  }
}

TEST(PhotonMc, SlabEnergyBalanceCloses) {
  for (double n : {1.0, 1.33, 1.5}) {
    PhotonMcSettings s;
    s.sigma_s = 100.0;
    s.sigma_a = 0.5;
    s.phase = HgPhase{0.9};
    s.thickness = 0.05;
    s.n = n;
    s.photons = 4000;
    s.batches = 10;
    const PhotonMcResult r = run_photon_mc(s);
    const double sum =
        r.specular.value + r.diffuse_reflectance.value + r.transmittance.value + r.absorbed.value;
    // Weight splitting at the faces is exact; only roulette (weights ~1e-4) perturbs the balance.
    EXPECT_NEAR(sum, 1.0, 2e-4) << "n=" << n;
    EXPECT_NEAR(r.specular.value, std::pow((n - 1) / (n + 1), 2), 1e-15);
    EXPECT_LE(r.unscattered_transmittance.value, r.transmittance.value);
  }
}

// A purely absorbing slab with index n: the unscattered light bounces between the faces,
// T = (1-R)^2 e^-tau / (1 - R^2 e^-2tau), diffuse R = (1-R)^2 R e^-2tau / (1 - R^2 e^-2tau).
TEST(PhotonMc, AbsorbingSlabWithFresnelFacesIsExact) {
  PhotonMcSettings s;
  s.sigma_s = 0.0;
  s.sigma_a = 1.0;
  s.thickness = 0.5;
  s.n = 2.0;
  s.photons = 40000;
  s.batches = 20;
  const PhotonMcResult r = run_photon_mc(s);
  const double R = 1.0 / 9.0, e = std::exp(-0.5), den = 1.0 - R * R * e * e;
  EXPECT_NEAR(r.transmittance.value, (1 - R) * (1 - R) * e / den, 5.0 * r.transmittance.err);
  EXPECT_NEAR(r.unscattered_transmittance.value, r.transmittance.value, 1e-15);
  EXPECT_NEAR(r.diffuse_reflectance.value, (1 - R) * (1 - R) * R * e * e / den,
              5.0 * r.diffuse_reflectance.err + 1e-4);
}

TEST(PhotonMc, DeterministicForASeedWhateverTheThreadCount) {
  PhotonMcSettings s;
  s.sigma_s = 1.0;
  s.sigma_a = 0.01;
  s.phase = HgPhase{0.8};
  s.plane_depths = {1.0, 3.0};
  s.theta_edges = {0.0, 0.05, 0.2, 1.0, kPi};
  s.r_edges = {0.0, 0.1, 1.0, 5.0};
  s.photons = 3000;
  s.batches = 12;
  s.seed = 42;
  PhotonMcResult a, b;
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    a = run_photon_mc(s);
  }
  b = run_photon_mc(s);
  for (size_t k = 0; k < a.planes.size(); ++k) {
    for (size_t i = 0; i < a.planes[k].angular.size(); ++i) {
      EXPECT_EQ(a.planes[k].angular[i].value, b.planes[k].angular[i].value);
      EXPECT_EQ(a.planes[k].angular[i].err, b.planes[k].angular[i].err);
    }
    for (size_t i = 0; i < a.planes[k].radial.size(); ++i)
      EXPECT_EQ(a.planes[k].radial[i].value, b.planes[k].radial[i].value);
  }
  s.seed = 43;
  const PhotonMcResult c = run_photon_mc(s);
  EXPECT_NE(a.planes[0].angular[0].value, c.planes[0].angular[0].value);
}

TEST(PhotonMc, RejectsBadSettings) {
  PhotonMcSettings s;
  s.sigma_s = -1.0;
  EXPECT_THROW(run_photon_mc(s), Error);
  s.sigma_s = 1.0;
  s.plane_depths = {2.0, 1.0};
  EXPECT_THROW(run_photon_mc(s), Error);
  s.plane_depths = {1.0};
  s.thickness = 0.5;
  EXPECT_THROW(run_photon_mc(s), Error);
  s.thickness = 2.0;
  s.theta_edges = {0.0, 4.0};
  EXPECT_THROW(run_photon_mc(s), Error);
}

}  // namespace
}  // namespace nimbus
