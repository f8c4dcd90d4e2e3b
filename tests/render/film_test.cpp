// The film: pixel means from sums and counts, dropped non-finite samples, extra layers.
#include "render/film.h"

#include <gtest/gtest.h>

#include <limits>

#include "nimbus/error.h"

namespace nimbus {
namespace {

TEST(Film, PixelMeansOverTheSamplesTaken) {
  Film film(3, 2);
  EXPECT_TRUE(film.add_sample(1, 0, Rgb(1.0, 2.0, 3.0)));
  EXPECT_TRUE(film.add_sample(1, 0, Rgb(3.0, 2.0, 1.0)));
  // A non-finite sample is dropped but counted: the pixel mean stays unbiased for the finite ones' sum.
  EXPECT_FALSE(film.add_sample(2, 1, Rgb(std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0)));
  EXPECT_TRUE(film.add_sample(2, 1, Rgb(4.0, 4.0, 4.0)));
  EXPECT_EQ(film.samples(1, 0), 2u);
  EXPECT_EQ(film.samples(2, 1), 2u);
  EXPECT_EQ(film.samples(0, 0), 0u);
  const Image img = film.resolve();
  ASSERT_EQ(img.width, 3);
  ASSERT_EQ(img.height, 2);
  EXPECT_FLOAT_EQ(img.pixel(1, 0)[0], 2.0f);
  EXPECT_FLOAT_EQ(img.pixel(1, 0)[1], 2.0f);
  EXPECT_FLOAT_EQ(img.pixel(1, 0)[2], 2.0f);
  EXPECT_FLOAT_EQ(img.pixel(2, 1)[0], 2.0f);
  EXPECT_FLOAT_EQ(img.pixel(0, 0)[0], 0.0f);  // no samples: black
}

TEST(Film, LayersHoldTheirOwnChannels) {
  Film film(2, 2);
  EXPECT_EQ(film.layer_index("rgb"), 0);
  const int depth = film.add_layer("depth", 1);
  EXPECT_EQ(film.layer_index("depth"), depth);
  EXPECT_EQ(film.layer_index("alpha"), -1);
  EXPECT_THROW(film.add_layer("depth", 1), Error);
  EXPECT_THROW(film.add_layer("empty", 0), Error);
  const double d1 = 2.0, d2 = 4.0;
  film.add_sample(0, 1, Rgb(1.0));
  film.add(depth, 0, 1, &d1);
  film.add_sample(0, 1, Rgb(1.0));
  film.add(depth, 0, 1, &d2);
  const std::vector<float> z = film.resolve_layer(depth);
  ASSERT_EQ(z.size(), 4u);
  EXPECT_FLOAT_EQ(z[2], 3.0f);  // pixel (0, 1): row 1 starts at index 2
  EXPECT_FLOAT_EQ(z[0], 0.0f);
}

}  // namespace
}  // namespace nimbus
