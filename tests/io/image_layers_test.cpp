// EXR output with alpha and layers, read back through OpenEXR itself (the names compositors see), and
// deep EXR written and read through the deep scanline API.
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfMultiPartInputFile.h>
#include <gtest/gtest.h>

#include "nimbus/error.h"
#include "nimbus/image.h"
#include "support/scratch_dir.h"

namespace nimbus {
namespace {

TEST(ImageLayers, RgbaAndLayersReadBackWithTheirNames) {
  const test::ScratchDir dir("image_layers");
  Image img(3, 2);
  for (size_t i = 0; i < img.rgb.size(); ++i) img.rgb[i] = 0.1f * float(i);
  img.alpha = {0.0f, 0.25f, 0.5f, 0.75f, 1.0f, 1.0f};
  img.channels.push_back({"Z", {1, 2, 3, 4, 5, 6}});
  img.channels.push_back({"direct.R", {7, 8, 9, 10, 11, 12}});
  write_exr(dir / "a.exr", img, {{"nimbus/spp", "4"}});

  Imf::InputFile file((dir / "a.exr").c_str());
  std::vector<std::string> names;
  for (auto it = file.header().channels().begin(); it != file.header().channels().end(); ++it)
    names.push_back(it.name());
  EXPECT_EQ(names, (std::vector<std::string>{"A", "B", "G", "R", "Z", "direct.R"}));
  std::vector<float> z(6, 0.0f);
  Imf::FrameBuffer fb;
  fb.insert("Z", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(z.data()), sizeof(float), 3 * sizeof(float)));
  file.setFrameBuffer(fb);
  file.readPixels(0, 1);
  EXPECT_EQ(z[4], 5.0f);

  ImageMetadata meta;
  const Image back = read_exr(dir / "a.exr", &meta);
  EXPECT_EQ(back.alpha, img.alpha);
  EXPECT_EQ(back.rgb, img.rgb);
  // An RGB file reads with no alpha.
  Image rgb(1, 1);
  write_exr(dir / "b.exr", rgb);
  EXPECT_TRUE(read_exr(dir / "b.exr").alpha.empty());
  // A channel of the wrong size, or one that shadows RGBA, is an error.
  img.channels.push_back({"A", {1, 2, 3, 4, 5, 6}});
  EXPECT_THROW(write_exr(dir / "c.exr", img), Error);
}

TEST(ImageLayers, DeepExrRoundTripsAndFlattens) {
  const test::ScratchDir dir("deep_exr");
  DeepImage deep;
  deep.width = 2;
  deep.height = 2;
  deep.offsets = {0, 2, 2, 3, 6};
  deep.samples = {{1, 2, 0.2f, 0.2f, 0.2f, 0.5f}, {3, 3, 0.4f, 0.0f, 0.0f, 1.0f},
                  {0.5f, 0.5f, 0, 0, 0.1f, 0.1f}, {1, 2, 0.1f, 0.1f, 0.1f, 0.2f},
                  {2, 3, 0.2f, 0.2f, 0.2f, 0.4f}, {3, 4, 0.3f, 0.3f, 0.3f, 0.6f}};
  write_deep_exr(dir / "d.exr", deep, {{"nimbus/spp", "1"}});
  const DeepImage back = read_deep_exr(dir / "d.exr");
  ASSERT_EQ(back.offsets, deep.offsets);
  for (size_t i = 0; i < deep.samples.size(); ++i) {
    EXPECT_EQ(back.samples[i].z, deep.samples[i].z);
    EXPECT_EQ(back.samples[i].z_back, deep.samples[i].z_back);
    EXPECT_EQ(back.samples[i].r, deep.samples[i].r);
    EXPECT_EQ(back.samples[i].a, deep.samples[i].a);
  }
  const Image flat = flatten(back);
  EXPECT_FLOAT_EQ(flat.alpha[0], 1.0f);              // 0.5 over 1
  EXPECT_FLOAT_EQ(flat.rgb[0], 0.2f + 0.5f * 0.4f);  // 0.2 + (1 - 0.5) 0.4
  EXPECT_FLOAT_EQ(flat.alpha[1], 0.0f);              // no samples
  EXPECT_FLOAT_EQ(flat.alpha[3], 1.0f - 0.8f * 0.6f * 0.4f);
  // A malformed deep image is not written.
  deep.offsets.back() = 7;
  EXPECT_THROW(write_deep_exr(dir / "e.exr", deep), Error);
}

}  // namespace
}  // namespace nimbus
