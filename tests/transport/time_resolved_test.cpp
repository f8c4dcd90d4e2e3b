// Time-resolved transport (issue 14): time-edge parsing, the closed forms (diffusion reflectance, the MFS
// delay moments) against independent quadratures and limits, and the photon Monte Carlo's time tallies:
// causality, time integral = steady tally, microscopic Beer-Lambert.  Short runs; tolerances from the
// estimated standard errors.
#include "transport/time_resolved.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "core/math.h"
#include "core/rng.h"
#include "nimbus/error.h"
#include "transport/photon_mc.h"

namespace nimbus {
namespace {

TEST(TimeEdges, ParsesListsAndRanges) {
  EXPECT_EQ(parse_time_edges("--t", "0,1.5,4"), (std::vector<double>{0.0, 1.5, 4.0}));
  EXPECT_EQ(parse_time_edges("--t", "1:3:4"), (std::vector<double>{1.0, 1.5, 2.0, 2.5, 3.0}));
  EXPECT_EQ(parse_time_edges("--t", "0:2:1").size(), 2u);
}

TEST(TimeEdges, RejectsBadInputNamingTheArgument) {
  for (const char* bad : {"", "1", "0,2,1", "0,1,1", "-1,2", "0,x", "0:1", "0:1:0", "0:1:2.5", "1:0:3",
                          "0:1:1e9", "0:1:-3", "0,inf"}) {
    try {
      parse_time_edges("--time-edges", bad);
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("--time-edges"), std::string::npos) << e.what();
    }
  }
}

// Integral of f over [0, inf) by the substitution t = u / (1 - u) and the midpoint rule.
template <typename F>
double integrate_half_line(F&& f, int n = 400000) {
  double sum = 0.0;
  for (int i = 0; i < n; ++i) {
    const double u = (i + 0.5) / n, t = u / (1.0 - u);
    sum += f(t) / ((1.0 - u) * (1.0 - u));
  }
  return sum / n;
}

TEST(DiffusionReflectance, IntegratesToTheSteadyDipoleReflectance) {
  // Each term is a first-passage (Levy) density in time: its integral with exp(-mu_a v t) is
  // exp(-z sqrt(mu_a / D)), so R = [exp(-z0 k) + exp(-z+ k)] / 2 with k = sqrt(mu_a / D).
  for (double mu_a : {0.0, 0.01, 0.1}) {
    for (double n : {1.0, 1.4}) {
      const double mu_sp = 1.0, A = n == 1.0 ? 1.0 : 2.95;
      const double D = 1.0 / (3.0 * (mu_a + mu_sp)), k = std::sqrt(mu_a / D);
      const double zp = 1.0 + 4.0 * A * D;
      const double expected = 0.5 * (std::exp(-k) + std::exp(-zp * k));
      const double got =
          integrate_half_line([&](double t) { return diffusion_reflectance_rate(t, mu_sp, mu_a, n, A); });
      EXPECT_NEAR(got, expected, 2e-3 * expected) << mu_a << " " << n;
    }
  }
  EXPECT_EQ(diffusion_reflectance_rate(0.0, 1.0, 0.0, 1.0), 0.0);
}

TEST(MfsDelay, BrownianLimitAndLaplaceDerivatives) {
  // a = 0: the delay of a 2-D Brownian angle with variance T per component per length:
  // mean T z^2 / 2, variance T^2 z^4 / 6.
  const double theta2 = 0.003, b = 1.0;
  for (double z : {0.1, 1.0, 5.0}) {
    const double T = theta2 * b / (1.0 - std::exp(-b * z));
    const DelayMoments m = mfs_delay_moments(z, b, 0.0, theta2);
    EXPECT_NEAR(m.mean, T * z * z / 2.0, 1e-12 * m.mean);
    EXPECT_NEAR(m.variance, T * T * z * z * z * z / 6.0, 1e-12 * m.variance);
  }
  // a > 0: mean and variance are the first two cumulants of the delay weighted by exp(-a tau), from the
  // Laplace transform 1 / cosh(z sqrt(a T)): finite differences of -ln cosh in a (where x = z / L is
  // not so small that ln cosh x loses its digits; the a -> 0 limit is the closed form above).
  for (double z : {0.5, 3.0, 30.0}) {
    for (double a : {0.01, 0.1, 1.0}) {
      const double T = theta2 * b / (1.0 - std::exp(-b * z));
      auto lnZ = [&](long double aa) { return -std::log(std::cosh(z * std::sqrt(aa * (long double)T))); };
      // Central differences with one Richardson step (errors of order h^4).
      auto d1 = [&](long double h) { return -(lnZ(a + h) - lnZ(a - h)) / (2 * h); };
      auto d2 = [&](long double h) { return (lnZ(a + h) - 2 * lnZ(a) + lnZ(a - h)) / (h * h); };
      const long double h = 0.05L * a;
      const double mean = double((4 * d1(h / 2) - d1(h)) / 3);
      const double var = double((4 * d2(h / 2) - d2(h)) / 3);
      const DelayMoments m = mfs_delay_moments(z, b, a, theta2);
      EXPECT_NEAR(m.mean, mean, 1e-6 * mean) << z << " " << a;
      EXPECT_NEAR(m.variance, var, 1e-5 * var) << z << " " << a;
    }
  }
  // Continuous where the variance switches to its series.
  const double T = 0.001, z = 1.0, a_switch = 0.05 * 0.05 / (T * z * z);
  const double theta2_s = T * (1.0 - std::exp(-z));
  EXPECT_NEAR(mfs_delay_moments(z, 1.0, a_switch * 0.999, theta2_s).variance,
              mfs_delay_moments(z, 1.0, a_switch * 1.001, theta2_s).variance, 1e-6 * T * T);
  EXPECT_THROW(mfs_delay_moments(0.0, 1.0, 0.0, 0.01), Error);
}

TEST(MfsDelay, DensityCarriesTheKernelsTotalAndMean) {
  // The series density integrates to W / cosh(z / L) (notes: the kernel's total) and its first moment
  // over that total is the closed-form mean: two independent routes to the same cumulants.
  const double theta2 = 0.004, b = 1.0;
  for (double z : {0.2, 2.0, 20.0}) {
    for (double a : {0.0, 0.01, 0.5}) {
      const double T = theta2 * b / (1.0 - std::exp(-b * z)), x = z * std::sqrt(a * T);
      const double total = std::exp(-a * z) * (1.0 - std::exp(-b * z)) / std::cosh(x);
      const double inf = std::numeric_limits<double>::infinity();
      EXPECT_NEAR(mfs_delay_within(0.0, inf, z, b, a, theta2), total, 1e-6 * total) << z << " " << a;
      // Bins add up; the first moment by the midpoint rule on fine bins.
      const DelayMoments m = mfs_delay_moments(z, b, a, theta2);
      const double top = 30.0 * T * z * z, dt = top / 20000;
      double parts = 0.0, first = 0.0;
      for (int i = 0; i < 20000; ++i) {
        const double t = (i + 0.5) * dt;
        first += t * mfs_delay_density(t, z, b, a, theta2) * dt;
        if (i % 2000 == 0) parts += mfs_delay_within(i * dt, (i + 2000) * dt, z, b, a, theta2);
      }
      EXPECT_NEAR(parts, total, 1e-6 * total);
      EXPECT_NEAR(first / total, m.mean, 1e-4 * m.mean) << z << " " << a;
    }
  }
}

TEST(PoissonDelay, MatchesADirectSimulationOfTheSmallAngleProcess) {
  // Deflections N(0, theta2) per component at Poisson(b) times along [0, z]; tau = 1/2 int |gamma|^2.
  // Simulated directly (no photon tracer) and conditioned on at least one scatter.
  const double z = 2.0, b = 1.5, theta2 = 1.0;
  const int batches = 20, per = 20000;
  std::vector<double> means, vars;
  for (int bt = 0; bt < batches; ++bt) {
    double s1 = 0.0, s2 = 0.0, n = 0.0;
    for (int i = 0; i < per; ++i) {
      Rng rng(9, uint64_t(bt) * per + i);
      double t = 0.0, gx = 0.0, gy = 0.0, tau = 0.0;
      bool scattered = false;
      while (true) {
        const double step = -std::log(1.0 - rng.uniform()) / b;
        if (t + step >= z) {
          tau += 0.5 * (gx * gx + gy * gy) * (z - t);
          break;
        }
        tau += 0.5 * (gx * gx + gy * gy) * step;
        t += step;
        const double r = std::sqrt(-2.0 * theta2 * std::log(1.0 - rng.uniform())),
                     phi = 2.0 * kPi * rng.uniform();
        gx += r * std::cos(phi);
        gy += r * std::sin(phi);
        scattered = true;
      }
      if (!scattered) continue;
      s1 += tau;
      s2 += tau * tau;
      n += 1.0;
    }
    means.push_back(s1 / n);
    vars.push_back(s2 / n - (s1 / n) * (s1 / n));
  }
  auto mean_err = [](const std::vector<double>& v) {
    double m = 0.0, q = 0.0;
    for (double x : v) m += x / v.size();
    for (double x : v) q += (x - m) * (x - m);
    return std::pair<double, double>{m, std::sqrt(q / (v.size() - 1) / v.size())};
  };
  const auto [m, em] = mean_err(means);
  const auto [var, ev] = mean_err(vars);
  const DelayMoments exact = poisson_delay_moments(z, b, theta2);
  EXPECT_NEAR(m, exact.mean, 5.0 * em);
  EXPECT_NEAR(var, exact.variance, 5.0 * ev);
  EXPECT_LT(ev, 0.02 * exact.variance);  // power: the Gaussian measure's variance is half of it here
  const DelayMoments gauss = mfs_delay_moments(z, b, 0.0, theta2);
  EXPECT_NEAR(gauss.mean, exact.mean, 1e-12 * exact.mean);
  EXPECT_GT(std::abs(var - gauss.variance), 10.0 * ev);
}

PhotonMcSettings small_slab(double sigma_a, double n, uint64_t seed) {
  PhotonMcSettings s;
  s.sigma_s = 1.0;
  s.sigma_a = sigma_a;
  s.phase = HgPhase{0.5};
  s.thickness = 2.0;
  s.n = n;
  s.photons = 20000;
  s.seed = seed;
  s.batches = 20;
  for (int i = 0; i <= 200; ++i) s.time_edges.push_back(0.1 * i);
  return s;
}

double sum(const TimeTally& t) {
  double v = t.before.value + t.after.value;
  for (const Estimate& e : t.bins) v += e.value;
  return v;
}

TEST(PhotonMcTime, TimeIntegralIsTheSteadyTallyOfTheSamePhotons) {
  for (double n : {1.0, 1.4}) {
    const PhotonMcSettings s = small_slab(0.1, n, 3);
    const PhotonMcResult r = run_photon_mc(s);
    EXPECT_NEAR(sum(r.reflect_time), r.diffuse_reflectance.value, 1e-12);
    EXPECT_NEAR(sum(r.transmit_time), r.transmittance.value, 1e-12);
    EXPECT_GT(r.transmit_time.after.value, 0.0);  // the late tail is kept, not lost
    // The steady tool (no time bins) gives the same numbers from the same photons.
    PhotonMcSettings steady = s;
    steady.time_edges.clear();
    const PhotonMcResult q = run_photon_mc(steady);
    EXPECT_EQ(q.diffuse_reflectance.value, r.diffuse_reflectance.value);
    EXPECT_EQ(q.transmittance.value, r.transmittance.value);
    // And another seed agrees within noise.
    steady.seed = 77;
    const PhotonMcResult o = run_photon_mc(steady);
    const double eR = std::hypot(o.diffuse_reflectance.err, r.diffuse_reflectance.err);
    EXPECT_NEAR(o.diffuse_reflectance.value, sum(r.reflect_time), 5.0 * eR);
  }
}

TEST(PhotonMcTime, NothingArrivesBeforeLightCould) {
  for (double n : {1.0, 1.4}) {
    const PhotonMcSettings s = small_slab(0.0, n, 5);
    const PhotonMcResult r = run_photon_mc(s);
    const double t_direct = n * s.thickness;  // the unscattered light arrives at n D
    double early = 0.0, at_direct = 0.0;
    for (size_t i = 0; i < r.transmit_time.bins.size(); ++i) {
      if (s.time_edges[i + 1] <= t_direct - 1e-9) early += r.transmit_time.bins[i].value;
      if (s.time_edges[i] <= t_direct && t_direct < s.time_edges[i + 1])
        at_direct = r.transmit_time.bins[i].value;
    }
    EXPECT_EQ(early, 0.0) << n;
    // All unscattered light but the part reflected twice inside (leaving at 3 n D; R^2 < 1e-3).
    EXPECT_GE(at_direct, 0.999 * r.unscattered_transmittance.value) << n;
    EXPECT_EQ(r.reflect_time.before.value, 0.0);
    EXPECT_GT(r.reflect_time.bins[1].value, 0.0);  // a backscatter within 0.05 of the face is possible
  }
}

TEST(PhotonMcTime, AbsorptionWeightsEachTimeByBeerLambert) {
  // Microscopic Beer-Lambert: R_a(t) = R_0(t) exp(-sigma_a t) (n = 1), exact and independent of the
  // scattering.  The 0.1-wide bins are weighted at their midpoints (error below 1e-3 here) and summed
  // in groups of 10 to compare where the noise allows a sharp test.
  const double sigma_a = 0.5;
  const PhotonMcResult r0 = run_photon_mc(small_slab(0.0, 1.0, 11));
  const PhotonMcResult ra = run_photon_mc(small_slab(sigma_a, 1.0, 12));
  int compared = 0;
  for (const bool transmit : {false, true}) {
    const TimeTally& t0 = transmit ? r0.transmit_time : r0.reflect_time;
    const TimeTally& ta = transmit ? ra.transmit_time : ra.reflect_time;
    for (size_t g = 0; g < 10; ++g) {
      double v0 = 0.0, e0 = 0.0, va = 0.0, ea = 0.0;
      for (size_t i = 10 * g; i < 10 * g + 10; ++i) {
        const double w = std::exp(-sigma_a * 0.1 * (double(i) + 0.5));
        v0 += w * t0.bins[i].value;
        e0 += std::pow(w * t0.bins[i].err, 2);
        va += ta.bins[i].value;
        ea += std::pow(ta.bins[i].err, 2);
      }
      const double err = std::sqrt(e0 + ea);
      if (!(v0 > 0.0) || err > 0.2 * v0) continue;  // too few photons to say anything
      ++compared;
      EXPECT_NEAR(va, v0, 5.0 * err + 1e-3 * v0) << (transmit ? "T" : "R") << " group " << g;
    }
  }
  EXPECT_GE(compared, 8);
}

}  // namespace
}  // namespace nimbus
