// The Fournier-Forand phase function (src/media/fournier_forand.h): the rearranged evaluation against
// the paper's form written out naively, normalisation, CDF and mean cosine against independent
// quadratures, the backscatter fraction against Mobley et al. 2002's Petzold number, the table's samples
// against the closed-form CDF (chi-square, with a power check), the spec parser and the peak split.
#include "media/fournier_forand.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <nlohmann/json.hpp>
#include <vector>

#include "core/math.h"
#include "core/rng.h"
#include "media/phase.h"
#include "nimbus/error.h"
#include "nimbus/scene.h"
#include "support/scenes.h"
#include "transport/phase_spec.h"
#include "transport/phase_split.h"

namespace nimbus {
namespace {

struct Params {
  double n, mu;
};
const Params kFfCases[] = {{1.10, 3.5835}, {1.05, 3.3}, {1.2, 4.5}, {1.3184, 5.0}};

// Mobley, Sundman & Boss 2002, eq. 5, as printed (no care for delta = 1).
double ff_naive(double psi, double n, double mu) {
  const double nu = (3.0 - mu) / 2.0, s2 = std::pow(std::sin(psi / 2.0), 2);
  const double d = 4.0 / (3.0 * (n - 1.0) * (n - 1.0)) * s2, d180 = 4.0 / (3.0 * (n - 1.0) * (n - 1.0));
  const double a =
      1.0 / (4.0 * kPi * (1.0 - d) * (1.0 - d) * std::pow(d, nu)) *
      (nu * (1.0 - d) - (1.0 - std::pow(d, nu)) + (d * (1.0 - std::pow(d, nu)) - nu * (1.0 - d)) / s2);
  const double b = (1.0 - std::pow(d180, nu)) / (16.0 * kPi * (d180 - 1.0) * std::pow(d180, nu)) *
                   (3.0 * std::cos(psi) * std::cos(psi) - 1.0);
  return a + b;
}

// 2 pi int_0^theta f(psi) sin(psi) dpsi with psi = theta t^k (k taming the psi^(mu - 5) peak) and
// composite Simpson in t.
double quad(double theta, double mu, const std::function<double(double)>& f) {
  const int k = std::max(4, int(std::ceil(3.0 / (mu - 3.0)))), N = 40000;
  auto g = [&](double t) {
    if (t <= 0.0) return 0.0;
    const double psi = theta * std::pow(t, k);
    return f(psi) * std::sin(psi) * theta * k * std::pow(t, k - 1);
  };
  double s = g(0.0) + g(1.0);
  for (int i = 1; i < N; ++i) s += g(double(i) / N) * (i % 2 ? 4.0 : 2.0);
  return 2.0 * kPi * s / (3.0 * N);
}

TEST(FournierForand, EvaluationMatchesThePrintedForm) {
  for (const Params& p : kFfCases) {
    const double K = 4.0 / (3.0 * (p.n - 1.0) * (p.n - 1.0));
    for (double psi = 1e-4; psi < kPi; psi *= 1.01) {
      const double delta = K * std::pow(std::sin(psi / 2.0), 2);
      if (std::abs(1.0 - delta) < 0.002) continue;  // the printed form cancels catastrophically there
      const double want = ff_naive(psi, p.n, p.mu);
      EXPECT_NEAR(ff_eval_theta(psi, p.n, p.mu), want, 1e-7 * want) << p.n << " " << p.mu << " " << psi;
    }
    // Smooth across delta = 1 (the cone where the printed form is 0/0).
    const double psi1 = 2.0 * std::asin(std::sqrt(1.0 / K));
    const double lo = ff_eval(std::cos(psi1 * 0.999), p.n, p.mu), mid = ff_eval(std::cos(psi1), p.n, p.mu),
                 hi = ff_eval(std::cos(psi1 * 1.001), p.n, p.mu);
    EXPECT_TRUE(std::isfinite(mid));
    EXPECT_NEAR(mid, 0.5 * (lo + hi), 1e-4 * mid);
  }
}

TEST(FournierForand, NormalisedCdfAndBackscatterAgainstQuadrature) {
  for (const Params& p : kFfCases) {
    auto P = [&](double psi) { return ff_eval_theta(psi, p.n, p.mu); };
    EXPECT_NEAR(quad(kPi, p.mu, P), 1.0, 1e-7) << p.n << " " << p.mu;
    for (double th : {1e-4, 1e-2, 0.1, 0.5, 0.5 * kPi, 2.5})
      EXPECT_NEAR(ff_cdf(th, p.n, p.mu), quad(th, p.mu, P), 1e-7) << p.n << " " << p.mu << " " << th;
    EXPECT_NEAR(ff_backscatter_fraction(p.n, p.mu), 1.0 - quad(0.5 * kPi, p.mu, P), 1e-7);
  }
  // Mobley et al. 2002: the Petzold average particle phase function, n = 1.10, mu = 3.5835, has B = 0.0183.
  EXPECT_NEAR(ff_backscatter_fraction(1.10, 3.5835), 0.0183, 1e-4);
  EXPECT_NEAR(ff_mobley_n(3.5835), 1.10, 1e-3);
  EXPECT_NEAR(ff_mobley_mu(0.0183), 3.5835, 0.01);
  // Along Mobley's curve B rises with mu (so the bisection has one root) and the inverse is exact.
  double last = 0.0;
  for (double mu = 3.05; mu <= 5.0; mu += 0.05) {
    const double b = ff_backscatter_fraction(ff_mobley_n(mu), mu);
    EXPECT_GT(b, last) << mu;
    last = b;
    EXPECT_NEAR(ff_mobley_mu(b), mu, 1e-8);
  }
  EXPECT_THROW(ff_mobley_mu(0.9), Error);
}

TEST(FournierForand, TableMatchesTheClosedForm) {
  for (const Params& p : kFfCases) {
    const TabulatedPhase t = make_ff_phase(p.n, p.mu);
    // The table's CDF at its nodes against the closed form.
    double worst = 0.0;
    for (size_t i = 0; i < t.theta.size(); i += 7)
      worst = std::max(worst, std::abs(t.cdf[i] - ff_cdf(t.theta[i], p.n, p.mu)));
    EXPECT_LT(worst, 2e-4) << p.n << " " << p.mu;
    // Mean cosine against an independent quadrature of the closed form.
    const double g =
        quad(kPi, p.mu, [&](double psi) { return std::cos(psi) * ff_eval_theta(psi, p.n, p.mu); });
    EXPECT_NEAR(phase_mean_cosine(Phase(t)), g, 2e-4) << p.n << " " << p.mu;
  }
}

// Chi-square of n samples in bins equiprobable under ff(n, mu_ref) against that closed form.
double chi_square(const Phase& phase, double n_ref, double mu_ref, int bins, int samples) {
  std::vector<double> edges{0.0};
  for (int b = 1; b < bins; ++b) {
    double lo = 0.0, hi = kPi;
    for (int it = 0; it < 100; ++it) {
      const double mid = 0.5 * (lo + hi);
      (ff_cdf(mid, n_ref, mu_ref) < double(b) / bins ? lo : hi) = mid;
    }
    edges.push_back(0.5 * (lo + hi));
  }
  edges.push_back(kPi);
  std::vector<double> count(bins, 0.0);
  for (int i = 0; i < samples; ++i) {
    Rng rng(11, i);
    const double u1 = rng.uniform(), u2 = rng.uniform();
    const double th = std::acos(std::clamp(phase_sample(phase, Vec3(0, 0, 1), u1, u2).z, -1.0, 1.0));
    const size_t b = std::upper_bound(edges.begin(), edges.end(), th) - edges.begin() - 1;
    count[std::min<size_t>(b, bins - 1)] += 1.0;
  }
  double chi2 = 0.0;
  for (int b = 0; b < bins; ++b) {
    const double e = (ff_cdf(edges[b + 1], n_ref, mu_ref) - ff_cdf(edges[b], n_ref, mu_ref)) * samples;
    chi2 += (count[b] - e) * (count[b] - e) / e;
  }
  return chi2;
}

TEST(FournierForand, SamplesFollowTheClosedForm) {
  // 40 bins (39 degrees of freedom): P(chi2 > 80) ~ 1e-4.  Bins near theta = 0 are down to 1e-7 rad
  // wide, so acos of the sampled direction's z must resolve them: theta is taken from z = cos theta,
  // good to ~1e-8 rad.  The equiprobable bins start above that.
  const Phase phase = make_ff_phase(1.10, 3.5835);
  EXPECT_LT(chi_square(phase, 1.10, 3.5835, 40, 200000), 80.0);
  // Power: a slightly different Fournier-Forand (mu 3.5835 -> 3.62) fails the same test clearly.
  EXPECT_GT(chi_square(Phase(make_ff_phase(1.10, 3.62)), 1.10, 3.5835, 40, 200000), 200.0);
}

TEST(FournierForand, SpecsAndPeakSplit) {
  const Phase a = parse_phase_spec("ff:1.1,3.5835");
  ASSERT_TRUE(std::holds_alternative<TabulatedPhase>(a));
  const Phase b = parse_phase_spec("ffb:0.0183");
  EXPECT_NEAR(phase_mean_cosine(a), phase_mean_cosine(b), 2e-3);
  for (const char* bad : {"ff:1.6,3.5", "ff:1.1,2.9", "ff:1.1", "ff:1.1,x", "ffb:0.9", "ffb:"})
    EXPECT_THROW(parse_phase_spec(bad), Error) << bad;
  // The models' split as for a Mie table: f = g^2 reached, parts non-negative and recombining.
  const PhaseSplit split(a, auto_peak_fraction(a));
  EXPECT_NEAR(split.f(), auto_peak_fraction(a), 2e-3);
  for (double mu : {-0.9, 0.0, 0.9, 0.999}) {
    EXPECT_GE(split.wide(mu), 0.0);
    EXPECT_NEAR(split.f() * split.peak(mu) + (1 - split.f()) * split.wide(mu), phase_eval(a, mu),
                1e-9 * phase_eval(a, mu));
  }
}

TEST(FournierForand, SceneFilePhase) {
  auto scene = [](const std::string& phase) {
    return parse_scene(
        nlohmann::json::parse(
            "{" + test::camera_json() +
            R"(, "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1},
                 "sigma_s": 1, "phase": )" +
            phase + R"(}], "lights": [{"type": "directional", "direction": [0, 0, -1], "irradiance": 1}]})"),
        "scene.json", ".");
  };
  const Scene s = scene(R"({"type": "fournier_forand", "n": 1.1, "mu": 3.5835})");
  EXPECT_NEAR(phase_mean_cosine(s.media[0].phase), phase_mean_cosine(Phase(make_ff_phase(1.1, 3.5835))),
              1e-12);
  for (const auto& [phase, field] : std::vector<std::pair<std::string, std::string>>{
           {R"({"type": "fournier_forand", "n": 2, "mu": 3.5})", "scene.json: /media/0/phase/n"},
           {R"({"type": "fournier_forand", "n": 1.1, "mu": 3})", "scene.json: /media/0/phase/mu"},
           {R"({"type": "fournier_forand", "n": 1.1})", "scene.json: /media/0/phase/mu"},
           {R"({"type": "fournier_forand", "n": 1.1, "mu": 3.5, "g": 0.9})",
            "scene.json: /media/0/phase/g"}}) {
    try {
      scene(phase);
      ADD_FAILURE() << phase;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace nimbus
