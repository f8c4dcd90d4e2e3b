// Analytic media (media/analytic_media.h): the closed-form transmittance of constant-density shapes
// against Beer-Lambert over a hand-computed chord and against an independent quadrature of the media's
// extinction; the pieces the path tracer tracks against; free flights over them against Beer-Lambert.
#include "media/analytic_media.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <vector>

#include "integrators/tracking.h"
#include "support/scenes.h"

namespace nimbus {
namespace {

using test::scene_from_json;

SceneMedia media_of(const std::string& media_json) {
  return SceneMedia(
      scene_from_json("{" + test::camera_json() + R"(, "media": )" + media_json +
                      R"(, "lights": [{"type": "directional", "direction": [0, 0, -1], "irradiance": 1}]})")
          .media);
}

// A transformed chromatic sphere (an ellipsoid) overlapping a chromatic box.
const char* kOverlapping = R"([
  {"shape": {"type": "sphere", "center": [0.1, 0, 0], "radius": 1}, "sigma_s": [1.0, 2.0, 3.0], "sigma_a": 0.25,
   "transform": {"scale": [1.5, 0.8, 1.2], "rotate": [{"axis": [1, 0.3, 0], "degrees": 35}]}},
  {"shape": {"type": "box", "min": [-0.5, -2, -0.3], "max": [0.7, 2, 0.4]}, "sigma_s": [0.5, 0.25, 4.0]}])";

// Optical depth of each channel along o + t d, t in (0, tmax), by the midpoint rule on the media's own
// extinction (SceneMedia::sigma_t: point-in-shape tests, no chords).
Rgb quadrature_depth(const SceneMedia& media, const Vec3& o, const Vec3& d, double tmax, int n) {
  Rgb tau(0.0);
  for (int i = 0; i < n; ++i) tau += media.sigma_t(o + d * ((i + 0.5) * tmax / n));
  return tau * (tmax / n);
}

TEST(AnalyticMedia, SphereTransmittanceIsBeerLambertOverTheChord) {
  const SceneMedia media = media_of(
      R"([{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": [1, 2, 3], "sigma_a": 0.5}])");
  const AnalyticMedia a(media);
  ASSERT_TRUE(a.active());
  const Rgb sigma_t(1.5, 2.5, 3.5);
  const double inf = std::numeric_limits<double>::infinity();
  for (double b : {0.0, 0.6, 0.99}) {
    // From outside through the whole chord 2 sqrt(1 - b^2), and cut short by tmax.
    const Rgb T = a.transmittance(Vec3(-3, 0, b), Vec3(1, 0, 0), inf);
    const double chord = 2.0 * std::sqrt(1.0 - b * b);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(T[k], std::exp(-sigma_t[k] * chord), 1e-12);
    const double tmax = 3.0 - std::sqrt(1.0 - b * b) + 0.3 * chord;
    const Rgb Tcut = a.transmittance(Vec3(-3, 0, b), Vec3(1, 0, 0), tmax);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(Tcut[k], std::exp(-sigma_t[k] * 0.3 * chord), 1e-12);
  }
  // From the centre outwards: the radius; a ray that misses: 1.
  EXPECT_NEAR(a.transmittance(Vec3(0.0), normalize(Vec3(1, 2, -1)), inf)[1], std::exp(-2.5), 1e-12);
  EXPECT_EQ(a.transmittance(Vec3(-3, 0, 1.01), Vec3(1, 0, 0), inf)[0], 1.0);
  EXPECT_EQ(a.transmittance(Vec3(-3, 0, 0), Vec3(-1, 0, 0), inf)[0], 1.0);
}

TEST(AnalyticMedia, TransformedOverlappingMediaMatchQuadrature) {
  const SceneMedia media = media_of(kOverlapping);
  const AnalyticMedia a(media);
  ASSERT_TRUE(a.active());
  const int n = 200000;
  for (const auto& [o, d, tmax] : {std::tuple{Vec3(-3, -0.2, 0.1), normalize(Vec3(1, 0.1, 0.05)), 6.0},
                                   std::tuple{Vec3(0.2, 0.1, 0.0), normalize(Vec3(-0.3, 1, 0.4)), 5.0},
                                   std::tuple{Vec3(0.0, -3, 0.2), normalize(Vec3(0.05, 1, -0.1)), 3.4}}) {
    const Rgb tau = quadrature_depth(media, o, d, tmax, n);
    const Rgb T = a.transmittance(o, d, tmax);
    // The midpoint rule errs by at most a step's depth at each of the (at most 4) boundaries crossed.
    const double tol = 4.0 * (tmax / n) * 7.0;
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(-std::log(T[k]), tau[k], tol) << "channel " << k;
    EXPECT_GT(tau[2], 1.0);  // the rays do cross the media
  }
}

TEST(AnalyticMedia, PiecesTileTheRayWithTheirExtinction) {
  // Grey media, so that each piece's majorant is its extinction: the pieces' depths add up to -log T.
  const SceneMedia media = media_of(R"([
    {"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": 2.0,
     "transform": {"scale": [1.5, 0.8, 1.2]}},
    {"shape": {"type": "box", "min": [-0.5, -2, -0.3], "max": [0.7, 2, 0.4]}, "sigma_s": 0.7, "sigma_a": 0.3},
    {"shape": {"type": "sphere", "center": [2, 0, 0], "radius": 0.3}, "sigma_s": 5.0}])");
  const AnalyticMedia a(media);
  const Vec3 o(-3, 0.05, 0.1), d = normalize(Vec3(1, 0.02, -0.01));
  double depth = 0.0, last = 0.0;
  int pieces = 0;
  a.traverse(o, d, 10.0, [&](double t0, double t1, double maj) {
    EXPECT_GE(t0, last);
    EXPECT_GT(t1, t0);
    EXPECT_NEAR(maj, max_component(media.sigma_t(o + d * (0.5 * (t0 + t1)))), 1e-12);
    depth += maj * (t1 - t0);
    last = t1;
    ++pieces;
    return true;
  });
  EXPECT_EQ(pieces, 4);  // sphere, sphere + box, sphere, the small sphere
  EXPECT_NEAR(depth, -std::log(a.transmittance(o, d, 10.0)[0]), 1e-12);
}

TEST(AnalyticMedia, GridsAndEmittersAreTrackedAgainstTheMajorantGrid) {
  EXPECT_FALSE(AnalyticMedia(media_of(R"([
    {"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": 1.0},
    {"shape": {"type": "cloud", "radius": 0.8, "resolution": 12}, "sigma_s": 2}])"))
                   .active());
  EXPECT_FALSE(AnalyticMedia(media_of(R"([
    {"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": 1.0, "emission": 0.5}])"))
                   .active());
  EXPECT_FALSE(AnalyticMedia(media_of("[]")).active());
  EXPECT_FALSE(AnalyticMedia().active());
}

// Free flights over the pieces (integrators/tracking.h): with grey media every tentative collision is
// real, and the share of flights that cross the media is their transmittance (binomial error).
TEST(Tracking, AnalyticFreeFlightsMatchBeerLambert) {
  const SceneMedia media = media_of(R"([
    {"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": 0.6,
     "transform": {"scale": [1.5, 0.8, 1.2]}},
    {"shape": {"type": "box", "min": [-0.5, -2, -0.3], "max": [0.7, 2, 0.4]}, "sigma_s": 0.2, "sigma_a": 0.1}])");
  const AnalyticMedia a(media);
  const Vec3 o(-3, 0.05, 0.1), d = normalize(Vec3(1, 0.02, -0.01));
  const double T = a.transmittance(o, d, 10.0)[0];
  const int n = 200000;
  int escaped = 0, nulls = 0;
  for (int i = 0; i < n; ++i) {
    Rng rng(7, uint64_t(i));
    escaped += track(a, o, d, 10.0, rng, [&](const Vec3& p, double maj) {
      nulls += std::abs(maj - media.sigma_t(p)[0]) > 1e-9 * maj;
      return false;
    });
  }
  EXPECT_EQ(nulls, 0);
  const double sigma = std::sqrt(T * (1.0 - T) / n);
  EXPECT_NEAR(double(escaped) / n, T, 5.0 * sigma);
  EXPECT_GT(T, 0.1);
  EXPECT_LT(T, 0.9);
}

// The growing march over the pieces (integrators/tracking.h, `mfs`'s march on constant-density shapes):
// the steps tile each piece exactly, none is longer than max_step or deeper than tau_step x scale at the
// piece's extinction, each sample sits at its offset (StepOffsets) in its step inside its piece, the optical depth sums to
// -log T, and a step that returns false ends the march. (The offsets: StepOffsets, below.)
TEST(Tracking, AnalyticMarchTilesThePiecesByOpticalDepth) {
  const SceneMedia media = media_of(R"([
    {"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": 2.0,
     "transform": {"scale": [1.5, 0.8, 1.2]}},
    {"shape": {"type": "box", "min": [-0.5, -2, -0.3], "max": [0.7, 2, 0.4]}, "sigma_s": 0.7, "sigma_a": 0.3},
    {"shape": {"type": "sphere", "center": [2, 0, 0], "radius": 0.3}, "sigma_s": 5.0}])");
  const AnalyticMedia a(media);
  const Vec3 o(-3, 0.05, 0.1), d = normalize(Vec3(1, 0.02, -0.01));
  const double tau_step = 0.2, max_step = 0.05, offset = 0.3;
  std::vector<std::array<double, 3>> pieces;  // t0, t1, majorant
  a.traverse(o, d, 10.0, [&](double t0, double t1, double maj) {
    return pieces.push_back({t0, t1, maj}), true;
  });
  ASSERT_EQ(pieces.size(), 4u);
  double depth = 0.0, growth = 0.0, end = 0.0;
  size_t piece = 0;
  int steps = 0;
  StepOffsets expected(offset);
  march_growing(
      a, o, d, 10.0, tau_step, max_step, offset, [&](double, double) { return 1.0 + growth; },
      [&](const Vec3& p, double t, double dt, double u) {
        EXPECT_NEAR(u, expected.next(), 1e-15);  // the golden-ratio offsets, step by step along the ray
        const double t_start = t - u * dt;
        while (piece < pieces.size() && t_start >= pieces[piece][1] - 1e-12) ++piece;
        EXPECT_LT(piece, pieces.size());
        if (piece >= pieces.size()) return false;
        const auto& [t0, t1, maj] = pieces[piece];
        // Contiguous within the piece: each step starts where the last ended (or at the piece's start).
        EXPECT_NEAR(t_start, end > t0 ? end : t0, 1e-12);
        EXPECT_LE(t_start + dt, t1 + 1e-12);
        EXPECT_LE(dt, max_step * (1 + 1e-12));
        EXPECT_LE(dt * maj, tau_step * (1.0 + growth) * (1 + 1e-12));
        EXPECT_NEAR((p - o).length(), t, 1e-12);
        depth += dt * maj;
        end = t_start + dt;
        if (std::abs(end - t1) < 1e-12) end = t1;
        growth += 0.5;  // later steps may be deeper
        ++steps;
        return true;
      });
  EXPECT_NEAR(end, pieces.back()[1], 1e-12);
  EXPECT_NEAR(depth, -std::log(a.transmittance(o, d, 10.0)[0]), 1e-9);
  EXPECT_GT(steps, 20);
  int taken = 0;
  march_growing(
      a, o, d, 10.0, tau_step, max_step, offset, [](double, double) { return 1.0; },
      [&](const Vec3&, double, double, double) { return ++taken < 3; });
  EXPECT_EQ(taken, 3);
}

// The growing march's step offsets (StepOffsets): each step's sample is uniform within it for a uniform first
// offset, and along the ray the offsets spread over [0, 1), so a falling integrand's steps do not all err
// the same way. The sum over the steps of exp(-tau) dt through a sphere of optical diameter 4 (20 steps of
// 0.2) against the exact 1 - exp(-4), over first offsets spread through [0, 1): with one offset for every step
// the error is as large as half a step's fall (10 %) at the ends of [0, 1), 5.8 % rms; with the golden-ratio
// offsets at most 1.9 %, 0.9 % rms; averaged over the first offset both are exact (within the quadrature's
// 1e-3).
TEST(Tracking, GrowingMarchOffsetsCancelAlongTheRay) {
  const SceneMedia media = media_of(R"([
    {"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": 2.0}])");
  const AnalyticMedia a(media);
  const Vec3 o(0, -3, 0), d(0, 1, 0);
  const double exact = 1.0 - std::exp(-4.0);
  double worst = 0.0, worst_shared = 0.0, mean = 0.0, mean_shared = 0.0, ms = 0.0, ms_shared = 0.0;
  constexpr int kOffsets = 1000;
  for (int i = 0; i < kOffsets; ++i) {
    const double u0 = (i + 0.5) / kOffsets;
    double sum = 0.0, shared = 0.0;
    march_growing(
        a, o, d, 10.0, 0.2, 10.0, u0, [](double, double) { return 1.0; },
        [&](const Vec3&, double t, double dt, double u) {
          sum += 2.0 * std::exp(-2.0 * (t - 2.0)) * dt;  // sigma_t T(t), the sphere entered at t = 2
          const double t_shared = t - u * dt + u0 * dt;
          shared += 2.0 * std::exp(-2.0 * (t_shared - 2.0)) * dt;
          return true;
        });
    worst = std::max(worst, std::abs(sum / exact - 1.0));
    worst_shared = std::max(worst_shared, std::abs(shared / exact - 1.0));
    mean += sum / kOffsets;
    mean_shared += shared / kOffsets;
    ms += std::pow(sum / exact - 1.0, 2) / kOffsets;
    ms_shared += std::pow(shared / exact - 1.0, 2) / kOffsets;
  }
  EXPECT_LT(std::sqrt(ms), 0.015);        // 0.9 %
  EXPECT_GT(std::sqrt(ms_shared), 0.04);  // 5.8 %
  EXPECT_LT(worst, 0.025);                // 1.9 %
  EXPECT_GT(worst_shared, 0.08);          // 10 %
  EXPECT_NEAR(mean / exact, 1.0, 1e-3);
  EXPECT_NEAR(mean_shared / exact, 1.0, 1e-3);
}

}  // namespace
}  // namespace nimbus
