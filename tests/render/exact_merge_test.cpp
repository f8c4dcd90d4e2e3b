// The film's fixed-point sums (render/film.h): each value rounded once to the grid (ties to even), sums
// independent of the order of the samples, the range rule (beauty samples beyond it dropped, other layers
// saturated, never an overflow), and renders of disjoint sample ranges whose states add up to the render
// of all the samples bit for bit, sums and pixels, for pathtrace and single on any number of threads.
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfIntAttribute.h>
#include <OpenEXR/ImfOutputFile.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

#include "nimbus/error.h"
#include "nimbus/render.h"
#include "render/film.h"
#include "render/film_layers.h"
#include "support/scenes.h"
#include "support/scratch_dir.h"

namespace nimbus {
namespace {

TEST(ExactFilm, RoundsToTheNearestIntegerTiesToEven) {
  EXPECT_EQ(film_round(0.0), 0);
  EXPECT_EQ(film_round(-0.0), 0);
  EXPECT_EQ(film_round(0.49999999999999994), 0);
  EXPECT_EQ(film_round(0.5), 0);
  EXPECT_EQ(film_round(1.5), 2);
  EXPECT_EQ(film_round(2.5), 2);
  EXPECT_EQ(film_round(-2.5), -2);
  EXPECT_EQ(film_round(-3.5), -4);
  EXPECT_EQ(film_round(2.75), 3);
  EXPECT_EQ(film_round(-1e-300), 0);
  // Beyond 2^52 every double is an integer: converted exactly (an independent 2^70 + 2^18).
  EXPECT_EQ(film_round(0x1p70 + 0x1p18), (FilmSum(1) << 70) + (FilmSum(1) << 18));
  EXPECT_EQ(film_round(-0x1p102), -(FilmSum(1) << 102));
  EXPECT_EQ(film_round(0x1p126), FilmSum(1) << 126);
  // Against the C library's rounding (ties to even in the default mode) over many magnitudes.
  std::mt19937_64 gen(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < 20000; ++i) {
    const double x = std::ldexp(u(gen), int(gen() % 62));  // |x| < 2^62: nearbyint's result fits int64
    ASSERT_EQ(film_round(x), FilmSum(int64_t(std::nearbyint(x)))) << x;
  }
}

TEST(ExactFilm, SumsAreExactAndIndependentOfTheOrder) {
  // Dyadic values k 2^-40 lie on the 2^-64 grid: their sum is known exactly in integers.
  std::mt19937_64 gen(11);
  std::vector<double> values;
  int64_t exact = 0;  // in units of 2^-40
  for (int i = 0; i < 1000; ++i) {
    const int64_t k = int64_t(gen() % (int64_t(1) << 50)) - (int64_t(1) << 49);
    exact += k;
    values.push_back(std::ldexp(double(k), -40));
  }
  // Then values over 30 decades, added in three orders: the sums agree to the bit.
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < 1000; ++i) values.push_back(std::pow(10.0, -15.0 + 24.0 * u(gen)) * (u(gen) - 0.3));
  std::vector<FilmSum> sums;
  for (int order = 0; order < 3; ++order) {
    Film film(1, 1);
    std::vector<double> v = values;
    if (order == 1) std::reverse(v.begin(), v.end());
    if (order == 2) std::shuffle(v.begin(), v.end(), gen);
    if (order == 0) {  // the dyadic part alone first: exactly its integer sum
      for (size_t i = 0; i < 1000; ++i) ASSERT_TRUE(film.add_sample(0, 0, Rgb(v[i])));
      EXPECT_EQ(film.state(1).layers[0].sums[0], FilmSum(exact) << 24);
      for (size_t i = 1000; i < v.size(); ++i) ASSERT_TRUE(film.add_sample(0, 0, Rgb(v[i])));
    } else {
      for (double x : v) ASSERT_TRUE(film.add_sample(0, 0, Rgb(x)));
    }
    sums.push_back(film.state(1).layers[0].sums[0]);
  }
  EXPECT_EQ(sums[0], sums[1]);
  EXPECT_EQ(sums[0], sums[2]);
  // The mean is the values' mean to the grid: within 2^-65 per value of the long double sum.
  long double reference = 0.0L;
  for (double x : values) reference += x;
  Film film(1, 1);
  for (double x : values) film.add_sample(0, 0, Rgb(x));
  EXPECT_NEAR(film.sum(0, 0, 0, 0), double(reference), 1e-14 * std::abs(double(reference)));
}

TEST(ExactFilm, ValuesBeyondTheRangeAreDroppedOrSaturated) {
  Film film(2, 1);
  const int depth = film.add_layer("depth", 1);
  const double limit = std::ldexp(1.0, kFilmSampleBits - kFilmFractionBits);  // 2^62
  EXPECT_TRUE(film.add_sample(0, 0, Rgb(limit, -limit, 1.0)));
  EXPECT_FALSE(film.add_sample(0, 0, Rgb(1.0, 2.0 * limit, 1.0)));  // dropped, counted
  EXPECT_FALSE(film.add_sample(0, 0, Rgb(INFINITY, 0.0, 0.0)));
  EXPECT_EQ(film.samples(0, 0), 3u);
  EXPECT_EQ(film.sum(0, 0, 0, 0), limit);
  EXPECT_EQ(film.sum(0, 0, 0, 1), -limit);
  const double big = 1e300, nan = NAN;
  film.add(depth, 1, 0, &big);  // saturated at the bound
  EXPECT_EQ(film.sum(depth, 1, 0, 0), limit);
  film.add(depth, 1, 0, &big);  // and the sum at 2^127 - 1 steps (2^63 as a double)
  EXPECT_EQ(film.sum(depth, 1, 0, 0), 2.0 * limit);
  EXPECT_EQ(film.state(1).layers[1].sums[1], (FilmSum(1) << 126) - 1 + (FilmSum(1) << 126));
  film.add(depth, 1, 0, &nan);  // adds nothing
  EXPECT_EQ(film.sum(depth, 1, 0, 0), 2.0 * limit);
}

Scene merge_scene(const std::string& integrator) {
  return test::scene_from_json("{" + test::camera_json(12, 10) + R"(,
    "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": 4.0,
               "sigma_a": 0.5, "phase": {"type": "hg", "g": 0.6}}],
    "lights": [{"type": "directional", "direction": [1, 1, -1], "irradiance": 2.0},
               {"type": "environment", "radiance": 0.2}],
    "film": {"layers": ["depth", "direct", "transmittance"]},
    "integrator": {"type": )" + integrator +
                               R"(, "spp": 7, "seed": 5}})");
}

TEST(ExactFilm, SampleRangesAddUpToTheRenderOfAllSamplesBitForBit) {
  // mfs: its outline pixels take 16 samples per pixel sample (edge_samples), so ranges add up there too.
  for (const std::string integrator :
       {R"("pathtrace")", R"("single")", R"("mfs", "photons": 4096, "beam_photons": 1024)"}) {
    SCOPED_TRACE(integrator);
    const Scene scene = merge_scene(integrator);
    RenderOptions all;
    all.threads = 2;
    const RenderResult whole = render(scene, all);
    // Ranges [0, 1), [1, 4), [4, 7) on 1, 3 and 2 threads, added in another order than their starts.
    FilmState sum;
    for (const auto& [start, count, threads] : {std::tuple{4, 3, 2}, {0, 1, 1}, {1, 3, 3}}) {
      RenderOptions part;
      part.sample_start = start;
      part.spp = count;
      part.threads = threads;
      part.tile_size = 5;
      const RenderResult r = render(scene, part);
      if (sum.layers.empty()) {
        sum = r.state;
        continue;
      }
      ASSERT_EQ(sum.layers.size(), r.state.layers.size());
      for (size_t l = 0; l < sum.layers.size(); ++l)
        for (size_t i = 0; i < sum.layers[l].sums.size(); ++i)
          sum.layers[l].sums[i] = film_add(sum.layers[l].sums[i], r.state.layers[l].sums[i]);
      for (size_t i = 0; i < sum.counts.size(); ++i) sum.counts[i] += r.state.counts[i];
    }
    // The power check: the comparison sees content (most pixels' sums are not 0).
    const auto zeros = std::count(whole.state.layers[0].sums.begin(), whole.state.layers[0].sums.end(), 0);
    EXPECT_LT(zeros, int64_t(whole.state.layers[0].sums.size() / 4));
    sum.spp = 7;
    EXPECT_EQ(sum.counts, whole.state.counts);
    // mfs's outline pixels took 16 per pixel sample (the other integrators' pixels 7 each).
    const uint32_t most = *std::max_element(whole.state.counts.begin(), whole.state.counts.end());
    EXPECT_EQ(most, integrator.find("mfs") != std::string::npos ? 16u * 7u : 7u);
    ASSERT_EQ(sum.layers.size(), whole.state.layers.size());
    for (size_t l = 0; l < sum.layers.size(); ++l) {
      EXPECT_EQ(sum.layers[l].name, whole.state.layers[l].name);
      EXPECT_TRUE(sum.layers[l].sums == whole.state.layers[l].sums) << sum.layers[l].name;
    }
    // The pixels of the added state, resolved as the driver does, equal the whole render's to the bit.
    Film film(12, 10);
    const FilmLayers layers(film, scene.film, true);
    film.restore(sum);
    const Image image = layers.resolve(film);
    ASSERT_EQ(image.rgb.size(), whole.image.rgb.size());
    EXPECT_EQ(0, std::memcmp(image.rgb.data(), whole.image.rgb.data(), image.rgb.size() * sizeof(float)));
    EXPECT_EQ(0,
              std::memcmp(image.alpha.data(), whole.image.alpha.data(), image.alpha.size() * sizeof(float)));
    ASSERT_EQ(image.channels.size(), whole.image.channels.size());
    for (size_t c = 0; c < image.channels.size(); ++c)
      EXPECT_EQ(0, std::memcmp(image.channels[c].data.data(), whole.image.channels[c].data.data(),
                               image.channels[c].data.size() * sizeof(float)))
          << image.channels[c].name;
  }
}

TEST(ExactFilm, AnOlderNimbussStateIsRefusedWithAClearError) {
  // The state as nimbus wrote it before the fixed-point film: double sums as _lo and _hi words.
  const test::ScratchDir scratch("exact_old_state");
  const auto file = scratch.path / "old.exr";
  Imf::Header header(2, 1);
  std::vector<uint32_t> words(2, 0), counts(2, 1);
  std::vector<float> rgb(2, 0.5f);
  Imf::FrameBuffer fb;
  for (const char* c : {"R", "G", "B"}) {
    header.channels().insert(c, Imf::Channel(Imf::FLOAT));
    fb.insert(c, Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(rgb.data()), sizeof(float), 0));
  }
  for (const char* c : {"nimbus_resume_rgb_0_lo", "nimbus_resume_rgb_0_hi", "nimbus_resume_count"}) {
    header.channels().insert(c, Imf::Channel(Imf::UINT));
    fb.insert(c, Imf::Slice(Imf::UINT, reinterpret_cast<char*>(c[14] == 'c' ? counts.data() : words.data()),
                            sizeof(uint32_t), 0));
  }
  header.insert("nimbus/resume_spp", Imf::IntAttribute(1));
  {
    Imf::OutputFile out(file.c_str(), header);
    out.setFrameBuffer(fb);
    out.writePixels(1);
  }
  try {
    read_exr_state(file);
    FAIL() << "no error";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("old.exr"), std::string::npos) << what;
    EXPECT_NE(what.find("older nimbus"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace nimbus
