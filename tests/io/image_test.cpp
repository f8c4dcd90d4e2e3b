// Images: EXR round trips, sRGB encoding, atomic writes that never lose an existing file, and the
// comparison metrics against hand-computed values.
#include "nimbus/image.h"

#include <gtest/gtest.h>
#include <png.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "io/atomic_file.h"
#include "nimbus/compare.h"
#include "nimbus/error.h"
#include "support/scratch_dir.h"

namespace nimbus {
namespace {

namespace fs = std::filesystem;

Image ramp(int w, int h) {
  Image img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      float* p = img.pixel(x, y);
      p[0] = 0.1f * x + 1e-7f * y;
      p[1] = 3.25f * y;
      p[2] = float(x * y) / 7.0f;
    }
  return img;
}

TEST(Image, ExrRoundTripIsExactWithMetadata) {
  const test::ScratchDir scratch("image_exr");
  const fs::path f = scratch.path / "a.exr";
  const Image img = ramp(13, 7);
  write_exr(f, img, {{"nimbus/scene", "{\"x\": 1}"}, {"nimbus/partial", "false"}});
  ImageMetadata meta;
  const Image back = read_exr(f, &meta);
  ASSERT_EQ(back.width, 13);
  ASSERT_EQ(back.height, 7);
  EXPECT_EQ(0, std::memcmp(back.rgb.data(), img.rgb.data(), img.rgb.size() * sizeof(float)));
  bool found = false;
  for (const auto& [k, v] : meta) found |= k == "nimbus/scene" && v == "{\"x\": 1}";
  EXPECT_TRUE(found);
}

TEST(Image, SrgbEncoding) {
  EXPECT_EQ(srgb_encode(0.0), 0.0);
  EXPECT_DOUBLE_EQ(srgb_encode(1.0), 1.0);
  EXPECT_NEAR(srgb_encode(0.5) * 255.0, 187.52, 0.01);           // the textbook 188
  EXPECT_NEAR(srgb_encode(0.0031308), 12.92 * 0.0031308, 1e-6);  // both branches meet
  EXPECT_NEAR(srgb_encode(0.0031308 + 1e-9), 12.92 * 0.0031308, 1e-6);
}

TEST(Image, PngHoldsSrgbBytesAndExposure) {
  const test::ScratchDir scratch("image_png");
  const fs::path& dir = scratch.path;
  Image img(4, 1);
  const float values[4] = {0.0f, 0.5f, 0.25f, 2.0f};
  for (int x = 0; x < 4; ++x) img.pixel(x, 0)[0] = img.pixel(x, 0)[1] = img.pixel(x, 0)[2] = values[x];
  write_png(dir / "a.png", img, 0.0);
  write_png(dir / "b.png", img, 1.0);
  for (const auto& [name, expect] : std::vector<std::pair<std::string, std::vector<int>>>{
           {"a.png", {0, 188, 137, 255}}, {"b.png", {0, 255, 188, 255}}}) {
    png_image png{};
    png.version = PNG_IMAGE_VERSION;
    ASSERT_TRUE(png_image_begin_read_from_file(&png, (dir / name).c_str()));
    png.format = PNG_FORMAT_RGB;
    std::vector<uint8_t> px(PNG_IMAGE_SIZE(png));
    ASSERT_TRUE(png_image_finish_read(&png, nullptr, px.data(), 0, nullptr));
    for (int x = 0; x < 4; ++x) EXPECT_EQ(px[x * 3], expect[x]) << name << " pixel " << x;
  }
}

// With alpha: straight colour, colour / alpha sRGB-encoded, alpha linear; alpha 0 is black.
TEST(Image, PngWithAlphaHoldsStraightColour) {
  const test::ScratchDir scratch("image_png_alpha");
  Image img(3, 1);
  img.alpha = {1.0f, 0.5f, 0.0f};
  const float premultiplied[3] = {0.5f, 0.125f, 0.0f};
  for (int x = 0; x < 3; ++x) img.pixel(x, 0)[0] = img.pixel(x, 0)[1] = img.pixel(x, 0)[2] = premultiplied[x];
  write_png(scratch.path / "a.png", img, 0.0, true);
  png_image png{};
  png.version = PNG_IMAGE_VERSION;
  ASSERT_TRUE(png_image_begin_read_from_file(&png, (scratch.path / "a.png").c_str()));
  EXPECT_TRUE(png.format & PNG_FORMAT_FLAG_ALPHA);
  png.format = PNG_FORMAT_RGBA;
  std::vector<uint8_t> px(PNG_IMAGE_SIZE(png));
  ASSERT_TRUE(png_image_finish_read(&png, nullptr, px.data(), 0, nullptr));
  // 0.5 / 1 and 0.125 / 0.5 = 0.25 in sRGB: 188 and 137.
  const int colour[3] = {188, 137, 0}, alpha[3] = {255, 128, 0};
  for (int x = 0; x < 3; ++x) {
    EXPECT_EQ(px[x * 4], colour[x]) << "pixel " << x;
    EXPECT_EQ(px[x * 4 + 3], alpha[x]) << "pixel " << x;
  }
}

TEST(Image, FailedWritesKeepTheOldFileAndLeaveNoTemporaries) {
  const test::ScratchDir scratch("image_atomic");
  const fs::path& dir = scratch.path;
  const fs::path f = dir / "keep.exr";
  write_exr(f, ramp(5, 5));
  const auto before = fs::file_size(f);
  EXPECT_THROW(atomic_write(f,
                            [](const fs::path& tmp) {
                              std::ofstream(tmp) << "half";
                              throw std::runtime_error("disk on fire");
                            }),
               Error);
  EXPECT_EQ(fs::file_size(f), before);
  EXPECT_NO_THROW(read_exr(f));
  int entries = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++entries;
  EXPECT_EQ(entries, 1);
  // A write to a missing folder is an error that names the path.
  try {
    write_png(dir / "missing" / "x.png", ramp(2, 2));
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("missing"), std::string::npos);
  }
  EXPECT_THROW(write_image(dir / "x.tiff", ramp(2, 2), {}, 0.0), Error);
}

TEST(Image, UnwritableDirectoryIsReported) {
  if (geteuid() == 0) GTEST_SKIP() << "root writes anywhere";
  const test::ScratchDir scratch("image_readonly");
  const fs::path& dir = scratch.path;
  chmod(dir.c_str(), 0555);
  EXPECT_THROW(write_exr(dir / "x.exr", ramp(2, 2)), Error);
  chmod(dir.c_str(), 0755);
}

TEST(Image, ReadErrorsNameTheFile) {
  const test::ScratchDir scratch("image_read");
  const fs::path& dir = scratch.path;
  std::ofstream(dir / "junk.exr") << "this is not an EXR file";
  try {
    read_exr(dir / "junk.exr");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind((dir / "junk.exr").string(), 0), 0u) << e.what();
  }
  EXPECT_THROW(read_exr(dir / "none.exr"), Error);
}

TEST(Compare, MetricsOnAnalyticImages) {
  Image b(8, 4), a(8, 4);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 8; ++x)
      for (int c = 0; c < 3; ++c) {
        b.pixel(x, y)[c] = 1.0f + x;
        a.pixel(x, y)[c] = 1.1f * (1.0f + x);
      }
  CompareResult r = compare_images(a, b);
  EXPECT_NEAR(r.mean_rel_error, 0.1, 1e-6);
  EXPECT_NEAR(r.mean_abs_rel_error, 0.1, 1e-6);
  // rel RMSE = sqrt(mean (0.1 v)^2) / mean v with v = 1..8 (each column 4 times).
  double s2 = 0, s1 = 0;
  for (int v = 1; v <= 8; ++v) {
    s2 += 0.01 * v * v;
    s1 += v;
  }
  EXPECT_NEAR(r.rel_rmse, std::sqrt(s2 / 8) / (s1 / 8), 1e-6);
  EXPECT_EQ(r.bins_used, 32);
  // 2x2 bins average pairs of columns; a constant +-x pattern cancels in bins.
  Image c = b;
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 8; ++x)
      for (int k = 0; k < 3; ++k) c.pixel(x, y)[k] = b.pixel(x, y)[k] + ((x + y) % 2 ? 0.5f : -0.5f);
  r = compare_images(c, b, {2, 0.0});
  EXPECT_EQ(r.bins_total, 8);
  EXPECT_NEAR(r.rel_rmse, 0.0, 1e-6);
  EXPECT_GT(compare_images(c, b).rel_rmse, 0.05);
  // Excluding dim bins.
  r = compare_images(a, b, {1, 1.0});
  EXPECT_EQ(r.bins_used, 16);  // columns 5..8 are >= the mean 4.5
  EXPECT_THROW(compare_images(a, Image(4, 4)), Error);
}

TEST(Compare, HeatmapColours) {
  Image b(3, 1), a(3, 1);
  for (int x = 0; x < 3; ++x)
    for (int c = 0; c < 3; ++c) b.pixel(x, 0)[c] = 1.0f;
  const float av[3] = {0.0f, 1.0f, 2.0f};
  for (int x = 0; x < 3; ++x)
    for (int c = 0; c < 3; ++c) a.pixel(x, 0)[c] = av[x];
  const Image h = error_heatmap(a, b, {}, 0.5);
  EXPECT_FLOAT_EQ(h.pixel(0, 0)[0], 0.0f);  // a << b: blue
  EXPECT_FLOAT_EQ(h.pixel(0, 0)[2], 1.0f);
  EXPECT_FLOAT_EQ(h.pixel(1, 0)[1], 1.0f);  // equal: white
  EXPECT_FLOAT_EQ(h.pixel(2, 0)[0], 1.0f);  // a >> b: red
  EXPECT_FLOAT_EQ(h.pixel(2, 0)[2], 0.0f);
}

}  // namespace
}  // namespace nimbus
