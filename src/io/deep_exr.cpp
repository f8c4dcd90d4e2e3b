// Deep images (nimbus/image.h): deep scanline EXR through OpenEXR's deep API, read back, and flattened.
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfDeepFrameBuffer.h>
#include <OpenEXR/ImfDeepScanLineInputFile.h>
#include <OpenEXR/ImfDeepScanLineOutputFile.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfPartType.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <fmt/format.h>

#include <array>
#include <cstddef>

#include "io/atomic_file.h"
#include "nimbus/error.h"
#include "nimbus/image.h"

namespace nimbus {

namespace fs = std::filesystem;

namespace {

// The channels and where each lives in a DeepSample.
struct DeepChannel {
  const char* name;
  size_t offset;
};
constexpr std::array<DeepChannel, 6> kDeepChannels = {{{"Z", offsetof(DeepSample, z)},
                                                       {"ZBack", offsetof(DeepSample, z_back)},
                                                       {"R", offsetof(DeepSample, r)},
                                                       {"G", offsetof(DeepSample, g)},
                                                       {"B", offsetof(DeepSample, b)},
                                                       {"A", offsetof(DeepSample, a)}}};

// Per channel, a pointer per pixel to its first sample's field (the deep frame buffer's layout).
void point_at_samples(DeepImage& img, std::array<std::vector<char*>, 6>& ptrs) {
  const size_t n = size_t(img.width) * size_t(img.height);
  for (size_t c = 0; c < kDeepChannels.size(); ++c) {
    ptrs[c].resize(n);
    for (size_t i = 0; i < n; ++i)
      ptrs[c][i] = reinterpret_cast<char*>(img.samples.data() + img.offsets[i]) + kDeepChannels[c].offset;
  }
}

void check_deep(const fs::path& path, const DeepImage& img) {
  const size_t n = size_t(std::max(img.width, 0)) * size_t(std::max(img.height, 0));
  if (img.width <= 0 || img.height <= 0 || img.offsets.size() != n + 1 || img.offsets.front() != 0 ||
      img.offsets.back() != img.samples.size())
    throw Error(fmt::format("{}: cannot write an empty or malformed deep image", path.string()));
  for (size_t i = 0; i < n; ++i)
    if (img.offsets[i + 1] < img.offsets[i] || img.offsets[i + 1] - img.offsets[i] > 0xffffffffu)
      throw Error(fmt::format("{}: malformed deep image (pixel {})", path.string(), i));
}

}  // namespace

void write_deep_exr(const fs::path& path, const DeepImage& img, const ImageMetadata& meta) {
  check_deep(path, img);
  DeepImage& data = const_cast<DeepImage&>(img);  // OpenEXR's slices take non-const pointers; only read
  const size_t n = size_t(img.width) * size_t(img.height);
  std::vector<uint32_t> counts(n);
  for (size_t i = 0; i < n; ++i) counts[i] = uint32_t(img.offsets[i + 1] - img.offsets[i]);
  std::array<std::vector<char*>, 6> ptrs;
  point_at_samples(data, ptrs);
  atomic_write(path, [&](const fs::path& tmp) {
    Imf::Header header(img.width, img.height);
    header.setType(Imf::DEEPSCANLINE);
    header.compression() = Imf::ZIPS_COMPRESSION;
    for (const DeepChannel& c : kDeepChannels) header.channels().insert(c.name, Imf::Channel(Imf::FLOAT));
    for (const auto& [key, value] : meta) header.insert(key, Imf::StringAttribute(value));
    Imf::DeepScanLineOutputFile file(tmp.c_str(), header);
    Imf::DeepFrameBuffer fb;
    fb.insertSampleCountSlice(Imf::Slice(Imf::UINT, reinterpret_cast<char*>(counts.data()), sizeof(uint32_t),
                                         sizeof(uint32_t) * img.width));
    for (size_t c = 0; c < kDeepChannels.size(); ++c)
      fb.insert(kDeepChannels[c].name,
                Imf::DeepSlice(Imf::FLOAT, reinterpret_cast<char*>(ptrs[c].data()), sizeof(char*),
                               sizeof(char*) * img.width, sizeof(DeepSample)));
    file.setFrameBuffer(fb);
    file.writePixels(img.height);
  });
}

DeepImage read_deep_exr(const fs::path& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw Error(fmt::format("{}: no such file", path.string()));
  try {
    Imf::DeepScanLineInputFile file(path.c_str());
    const Imath::Box2i dw = file.header().dataWindow();
    DeepImage img;
    img.width = dw.max.x - dw.min.x + 1;
    img.height = dw.max.y - dw.min.y + 1;
    const size_t n = size_t(img.width) * size_t(img.height);
    std::vector<uint32_t> counts(n);
    const size_t row = size_t(img.width);
    const ptrdiff_t origin = ptrdiff_t(dw.min.x) + ptrdiff_t(dw.min.y) * ptrdiff_t(row);
    // The slices first (their pointer tables are filled once the sample counts are known), then the
    // counts, then the samples.
    std::array<std::vector<char*>, 6> ptrs;
    for (auto& p : ptrs) p.resize(n);
    Imf::DeepFrameBuffer fb;
    fb.insertSampleCountSlice(Imf::Slice(Imf::UINT, reinterpret_cast<char*>(counts.data() - origin),
                                         sizeof(uint32_t), sizeof(uint32_t) * row));
    for (size_t c = 0; c < kDeepChannels.size(); ++c) {
      if (!file.header().channels().findChannel(kDeepChannels[c].name)) continue;
      fb.insert(kDeepChannels[c].name,
                Imf::DeepSlice(Imf::FLOAT, reinterpret_cast<char*>(ptrs[c].data() - origin), sizeof(char*),
                               sizeof(char*) * row, sizeof(DeepSample)));
    }
    file.setFrameBuffer(fb);
    file.readPixelSampleCounts(dw.min.y, dw.max.y);
    img.offsets.assign(n + 1, 0);
    for (size_t i = 0; i < n; ++i) img.offsets[i + 1] = img.offsets[i] + counts[i];
    img.samples.assign(img.offsets.back(), DeepSample{});
    point_at_samples(img, ptrs);
    file.readPixels(dw.min.y, dw.max.y);
    return img;
  } catch (const std::exception& e) {
    throw Error(fmt::format("{}: cannot read deep EXR: {}", path.string(), e.what()));
  }
}

Image flatten(const DeepImage& img) {
  Image out(img.width, img.height);
  out.alpha.assign(size_t(img.width) * img.height, 0.0f);
  for (size_t i = 0; i + 1 < img.offsets.size(); ++i) {
    double r = 0.0, g = 0.0, b = 0.0, a = 0.0;  // front to back: C += (1 - A) c, A += (1 - A) a
    for (uint64_t k = img.offsets[i]; k < img.offsets[i + 1]; ++k) {
      const DeepSample& s = img.samples[k];
      const double w = 1.0 - a;
      r += w * s.r;
      g += w * s.g;
      b += w * s.b;
      a += w * s.a;
    }
    out.rgb[3 * i] = float(r);
    out.rgb[3 * i + 1] = float(g);
    out.rgb[3 * i + 2] = float(b);
    out.alpha[i] = float(a);
  }
  return out;
}

}  // namespace nimbus
