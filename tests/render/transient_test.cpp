// Transient renders (film.time_bins, docs/transient.md): the bins sum to the steady image, which stays bit
// for bit the image of a render without bins, for any thread count; causality (nothing arrives before the
// shortest geometric path light -> medium -> camera); first-order scattering in a thin slab against a 1-D
// quadrature of the time-resolved single-scatter radiance; microscopic Beer-Lambert (with the camera and
// the light inside one homogeneous medium, absorption weights every path by exp(-sigma_a s)); bad bins.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "core/math.h"
#include "nimbus/error.h"
#include "nimbus/render.h"
#include "support/scenes.h"

namespace nimbus {
namespace {

// The determinism test's scene (a sphere and a procedural cloud; sun, point light, constant sky) with a
// diffuse floor and a sphere light, so that every kind of contribution is binned.
std::string mixed_scene(const std::string& film) {
  return "{" + test::camera_json(13, 11, 40.0, 4.0) + R"(,
    "media": [{"shape": {"type": "sphere", "center": [0.3, 0, 0], "radius": 0.8}, "sigma_s": [2.0, 3.0, 4.0],
               "sigma_a": 0.1, "phase": {"type": "hg", "g": 0.8}},
              {"shape": {"type": "cloud", "center": [-0.4, 0.2, 0.1], "radius": 0.9, "seed": 5, "resolution": 16},
               "sigma_s": 6.0, "sigma_a": 0.05, "phase": {"type": "double_hg", "g1": 0.9, "g2": -0.2, "w": 0.8}}],
    "surfaces": [{"shape": {"type": "box", "min": [-3, -3, -1.6], "max": [3, 3, -1.2]},
                  "material": {"type": "diffuse", "albedo": 0.5}}],
    "lights": [{"type": "directional", "direction": [-0.5, 0.6, -0.6], "irradiance": 2.0, "angular_diameter_deg": 1},
               {"type": "point", "position": [0.5, -1.5, 1.2], "intensity": 2.0},
               {"type": "sphere", "center": [-1.2, -0.5, 1.0], "radius": 0.3, "power": 20.0},
               {"type": "environment", "radiance": [0.1, 0.15, 0.3]}],
    "integrator": {"type": "pathtrace", "spp": 3, "seed": 3})" +
         film + "}";
}

RenderResult render_threads(const Scene& scene, int threads) {
  RenderOptions opt;
  opt.threads = threads;
  opt.tile_size = 4;
  return render(scene, opt);
}

// The time bins' pixel sums (channel c: 0..2) per slot, under- and overflow included.
std::vector<double> bin_totals(const Image& transient, int channel) {
  std::vector<double> totals;
  for (size_t k = size_t(channel); k < transient.channels.size(); k += 3) {
    double sum = 0.0;
    for (float v : transient.channels[k].data) sum += v;
    totals.push_back(sum);
  }
  return totals;
}

TEST(Transient, BinsSumToTheSteadyImageWhichIsUnchangedForAnyThreadCount) {
  const Scene steady_scene = test::scene_from_json(mixed_scene(""));
  const Scene scene = test::scene_from_json(mixed_scene(R"(, "film": {"time_bins": [2, 12, 25]})"));
  const RenderResult plain = render_threads(steady_scene, 2);
  const RenderResult one = render_threads(scene, 1), three = render_threads(scene, 3);
  ASSERT_EQ(plain.image.rgb.size(), one.image.rgb.size());
  EXPECT_EQ(0, std::memcmp(plain.image.rgb.data(), one.image.rgb.data(), one.image.rgb.size() * 4));
  EXPECT_EQ(0, std::memcmp(one.image.rgb.data(), three.image.rgb.data(), one.image.rgb.size() * 4));
  EXPECT_TRUE(plain.transient.rgb.empty());
  ASSERT_EQ(one.transient.channels.size(), size_t(3 * 27));
  EXPECT_EQ(one.transient.channels[0].name, "time_under.R");
  EXPECT_EQ(one.transient.channels[5].name, "time0000.B");
  for (size_t k = 0; k < one.transient.channels.size(); ++k)
    EXPECT_EQ(0, std::memcmp(one.transient.channels[k].data.data(), three.transient.channels[k].data.data(),
                             one.transient.channels[k].data.size() * 4))
        << one.transient.channels[k].name;
  // Per pixel and channel: the bins' sum against the steady value, to float rounding.
  double largest = 0.0;
  const size_t n = size_t(one.image.width) * size_t(one.image.height);
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) {
      double sum = 0.0;
      for (const ImageChannel& ch : one.transient.channels)
        if (ch.name.back() == "RGB"[c]) sum += ch.data[i];
      const double steady = one.image.rgb[3 * i + size_t(c)];
      EXPECT_NEAR(sum, steady, 1e-5 * std::abs(steady) + 1e-7) << "pixel " << i << " channel " << c;
      largest = std::max(largest, steady);
    }
  // Power: the light really is spread over several bins, and little is outside [t0, t1).
  const std::vector<double> red = bin_totals(one.transient, 0);
  int used = 0;
  for (double v : red) used += v > 0.01 * red[1];
  EXPECT_GT(largest, 0.0);
  EXPECT_GE(used, 5);
}

// A transparent film leaves the environment seen directly out of the bins as out of the image; a region's
// bins are the full render's bins of its pixels.
TEST(Transient, TransparentFilmsAndRegionsKeepTheBinsSummingToTheImage) {
  const Scene scene =
      test::scene_from_json(mixed_scene(R"(, "film": {"transparent": true, "time_bins": [2, 12, 10]})"));
  RenderOptions full_opt, region_opt;
  full_opt.threads = region_opt.threads = 2;
  region_opt.region = Region{3, 2, 9, 7};
  const RenderResult full = render(scene, full_opt), crop = render(scene, region_opt);
  ASSERT_EQ(crop.transient.width, 6);
  for (int y = 0; y < crop.image.height; ++y)
    for (int x = 0; x < crop.image.width; ++x) {
      const size_t i = size_t(y) * 6 + size_t(x),
                   j = size_t(y + 2) * size_t(full.image.width) + size_t(x + 3);
      double sum = 0.0;
      for (size_t k = 0; k < crop.transient.channels.size(); ++k) {
        EXPECT_EQ(crop.transient.channels[k].data[i], full.transient.channels[k].data[j]);
        if (k % 3 == 2) sum += crop.transient.channels[k].data[i];  // blue: the sky's strongest channel
      }
      EXPECT_NEAR(sum, crop.image.rgb[3 * i + 2], 1e-5 * std::abs(crop.image.rgb[3 * i + 2]) + 1e-7);
    }
}

// Path lengths of single scattering in a slab |y| < 0.5 seen by a camera at (0, -5, 0) looking along +y,
// a point light at kLight outside it: s(t) = t + |x(t) - light|, x(t) = (0, -5 + t, 0).
const Vec3 kLight{0.8, -2.0, 0.3};
constexpr double kSigmaS = 0.4, kSigmaA = 0.1, kIntensity = 3.0;

std::string slab_scene(int max_events, double sigma_a, const std::string& bins) {
  return R"({"camera": {"position": [0, -5, 0], "look_at": [0, 0, 0], "up": [0, 0, 1], "fov_y_deg": 0.01,
               "width": 1, "height": 1},
    "media": [{"shape": {"type": "box", "min": [-60, -0.5, -60], "max": [60, 0.5, 60]},
               "sigma_s": )" +
         std::to_string(kSigmaS) + R"(, "sigma_a": )" + std::to_string(sigma_a) +
         R"(, "phase": {"type": "isotropic"}}],
    "lights": [{"type": "point", "position": [0.8, -2.0, 0.3], "intensity": 3.0}],
    "integrator": {"type": "pathtrace", "spp": 1, "seed": 1, "max_events": )" +
         std::to_string(max_events) + R"(},
    "film": {"time_bins": )" +
         bins + "}}";
}

// The first-order radiance in each of n bins over [t0, t1): a midpoint quadrature over the camera ray
// inside the slab (t in [4.5, 5.5]) of sigma_s e^{-sigma_t (t - 4.5)} / (4 pi) I / r^2 e^{-sigma_t l},
// l the part of the light's segment inside the slab.
std::vector<double> single_scatter_bins(double t0, double t1, int n) {
  std::vector<double> bins(size_t(n), 0.0);
  const double sigma_t = kSigmaS + kSigmaA;
  const int steps = 400000;
  const double dt = 1.0 / steps;
  for (int i = 0; i < steps; ++i) {
    const double t = 4.5 + (i + 0.5) * dt;
    const Vec3 x{0.0, -5.0 + t, 0.0};
    const double r = length(x - kLight);
    const double inside = r * (x.y + 0.5) / (x.y - kLight.y);
    const double L = kSigmaS * std::exp(-sigma_t * (t - 4.5)) / (4.0 * kPi) * kIntensity / (r * r) *
                     std::exp(-sigma_t * inside) * dt;
    const double s = t + r;
    if (s >= t0 && s < t1) bins[size_t((s - t0) / (t1 - t0) * n)] += L;
  }
  return bins;
}

// Mean and standard error over independent renders (seeds) of one pixel's red time bins.
void seed_statistics(const std::string& json, int renders, int spp, std::vector<double>* mean,
                     std::vector<double>* error) {
  std::vector<std::vector<double>> runs;
  for (int k = 0; k < renders; ++k) {
    RenderOptions opt;
    opt.spp = spp;
    opt.seed = uint64_t(100 + k);
    opt.threads = 2;
    const RenderResult r = render(test::scene_from_json(json), opt);
    runs.push_back(bin_totals(r.transient, 0));
    if (k == 0) {  // the bins of this run sum to its steady image
      double sum = 0.0, image = 0.0;
      for (double v : runs.back()) sum += v;
      for (size_t i = 0; i < r.image.rgb.size(); i += 3) image += r.image.rgb[i];
      EXPECT_NEAR(sum, image, 1e-5 * image);
    }
  }
  const size_t slots = runs[0].size();
  mean->assign(slots, 0.0);
  error->assign(slots, 0.0);
  for (size_t b = 0; b < slots; ++b) {
    for (const auto& run : runs) (*mean)[b] += run[b] / renders;
    double var = 0.0;
    for (const auto& run : runs) var += (run[b] - (*mean)[b]) * (run[b] - (*mean)[b]);
    (*error)[b] = std::sqrt(var / (renders - 1) / renders);
  }
}

TEST(Transient, SingleScatteringInAThinSlabMatchesTheQuadratureBinByBin) {
  const double t0 = 5.0, t1 = 9.0;
  const int n = 16;
  std::vector<double> mean, error;
  seed_statistics(slab_scene(1, kSigmaA, "[5.0, 9.0, 16]"), 10, 8000, &mean, &error);
  const std::vector<double> exact = single_scatter_bins(t0, t1, n);
  double total = 0.0;
  for (double v : exact) total += v;
  ASSERT_GT(total, 0.0);
  EXPECT_EQ(mean.front(), 0.0);  // underflow
  EXPECT_EQ(mean.back(), 0.0);   // overflow
  for (int b = 0; b < n; ++b) {
    SCOPED_TRACE(b);
    // Quadrature: the bins' edges cut the steps (1 / 400000 of the path each): well below the noise.
    EXPECT_LT(std::abs(mean[size_t(b) + 1] - exact[size_t(b)]), 5.0 * error[size_t(b) + 1] + 1e-5 * total);
    if (exact[size_t(b)] > 0.05 * total) EXPECT_LT(error[size_t(b) + 1], 0.05 * exact[size_t(b)]);  // power
  }
}

TEST(Transient, NothingArrivesBeforeTheShortestPathFromTheLightThroughTheMedium) {
  // Every path ends on the camera ray inside the slab (t >= 4.5) at x_n, so s >= min_t (t + |x(t) -
  // light|) = 4.5 + |(0, -0.5, 0) - light| = 6.2264... (ds/dt > 0), whatever the scatters before x_n.
  const double s_min = 4.5 + length(Vec3{0.0, -0.5, 0.0} - kLight);
  const double t0 = 5.0, t1 = 9.0;
  const int n = 64;
  RenderOptions opt;
  opt.spp = 4000;
  opt.threads = 2;
  const RenderResult r = render(test::scene_from_json(slab_scene(0, 0.0, "[5.0, 9.0, 64]")), opt);
  const std::vector<double> bins = bin_totals(r.transient, 0);
  EXPECT_EQ(bins.front(), 0.0);
  const double dt = (t1 - t0) / n;
  const int first = int((s_min - t0) / dt);  // the bin that holds s_min
  for (int b = 0; b < first; ++b) EXPECT_EQ(bins[size_t(b) + 1], 0.0) << "bin " << b << " ends before s_min";
  EXPECT_GT(bins[size_t(first) + 1] + bins[size_t(first) + 2], 0.0);  // power: light arrives right after
  EXPECT_GT(bins.back(), 0.0);                                        // multiple scattering: a tail past t1
}

// Camera and point light inside one large homogeneous medium: every path lies in it, so absorption
// weights a path of length s by exactly exp(-sigma_a s). Bins of width dt: the ratio lies between the
// weights at the bin's edges.
TEST(Transient, AbsorptionWeightsEveryBinByBeerLambertOfItsPathLength) {
  auto scene = [](double sigma_a) {
    return std::string(R"({"camera": {"position": [0, -1, 0], "look_at": [0, 0, 0], "up": [0, 0, 1],
                 "fov_y_deg": 30, "width": 1, "height": 1},
      "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 50}, "sigma_s": 1.0,
                 "sigma_a": )") +
           std::to_string(sigma_a) + R"(, "phase": {"type": "hg", "g": 0.5}}],
      "lights": [{"type": "point", "position": [0.4, 0.5, 0.2], "intensity": 1.0}],
      "integrator": {"type": "pathtrace", "spp": 1, "seed": 1, "max_events": 6},
      "film": {"time_bins": [0.0, 6.0, 12]}})";
  };
  const double sigma_a = 0.4, dt = 0.5;
  std::vector<double> clear, clear_err, absorbing, absorbing_err;
  seed_statistics(scene(0.0), 8, 20000, &clear, &clear_err);
  seed_statistics(scene(sigma_a), 8, 20000, &absorbing, &absorbing_err);
  int checked = 0;
  for (int b = 0; b < 12; ++b) {
    SCOPED_TRACE(b);
    const double lo = std::exp(-sigma_a * (b + 1) * dt), hi = std::exp(-sigma_a * b * dt);
    const double a = absorbing[size_t(b) + 1], c = clear[size_t(b) + 1];
    const double noise = 5.0 * std::hypot(absorbing_err[size_t(b) + 1], hi * clear_err[size_t(b) + 1]);
    EXPECT_GE(a, lo * c - noise);
    EXPECT_LE(a, hi * c + noise);
    // Power: where there is light, the noise is well below the spread the absorption makes.
    if (c > 0.05 * clear[2] && noise < 0.3 * (1.0 - std::exp(-sigma_a * b * dt)) * c) ++checked;
  }
  EXPECT_GE(checked, 4);
}

TEST(Transient, BadBinsAndOtherIntegratorsAreRefusedNamingTheField) {
  for (const std::string bins : {"[]", "[1, 2]", "[2, 1, 4]", "[-1, 2, 4]", "[0, 2, 0]", "[0, 2, 2.5]",
                                 "[0, 2, 1e9]", "\"x\"", "[0, 2, 3, 4]"}) {
    SCOPED_TRACE(bins);
    try {
      test::scene_from_json(slab_scene(1, 0.1, bins));
      ADD_FAILURE() << "accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("time_bins"), std::string::npos) << e.what();
    }
  }
  // Too many values for memory: a 4000 x 4000 image with 10000 bins.
  EXPECT_THROW(test::scene_from_json(R"({"camera": {"position": [0, -5, 0], "look_at": [0, 0, 0],
      "width": 4000, "height": 4000}, "media": [], "lights": [], "film": {"time_bins": [0, 1, 10000]}})"),
               Error);
  RenderOptions opt;
  opt.integrator = "single";
  try {
    render(test::scene_from_json(slab_scene(1, 0.1, "[5, 9, 4]")), opt);
    ADD_FAILURE() << "single accepted time bins";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("film.time_bins"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace nimbus
