// Image files (nimbus/image.h): EXR read and write (RGB, alpha, layers), sRGB PNG output, both written
// atomically. Deep EXR: io/deep_exr.cpp; the resume state beside the image: io/exr_state.cpp.
#include "nimbus/image.h"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <fmt/format.h>
#include <png.h>

#include <algorithm>
#include <cmath>

#include "io/atomic_file.h"
#include "io/exr_state.h"
#include "nimbus/error.h"

namespace nimbus {

namespace fs = std::filesystem;

Image::Image(int w, int h) : width(w), height(h) {
  if (w <= 0 || h <= 0) throw Error(fmt::format("image size {}x{}: must be positive", w, h));
  if (int64_t(w) * h > (int64_t(1) << 28)) throw Error(fmt::format("image size {}x{}: too large", w, h));
  rgb.assign(size_t(w) * h * 3, 0.0f);
}

double srgb_encode(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x <= 0.0031308 ? 12.92 * x : 1.055 * std::pow(x, 1.0 / 2.4) - 0.055;
}

namespace {

void check_image(const fs::path& path, const Image& img) {
  const size_t n = size_t(std::max(img.width, 0)) * size_t(std::max(img.height, 0));
  if (img.width <= 0 || img.height <= 0 || img.rgb.size() != n * 3 ||
      (!img.alpha.empty() && img.alpha.size() != n))
    throw Error(fmt::format("{}: cannot write an empty or malformed image", path.string()));
  if (img.display_width != 0 &&
      (img.origin_x < 0 || img.origin_y < 0 || int64_t(img.origin_x) + img.width > img.display_width ||
       int64_t(img.origin_y) + img.height > img.display_height))
    throw Error(fmt::format("{}: the image's data window is not inside its display window", path.string()));
  for (const ImageChannel& c : img.channels)
    if (c.data.size() != n || c.name.empty() || c.name == "R" || c.name == "G" || c.name == "B" ||
        c.name == "A")
      throw Error(fmt::format("{}: malformed image channel '{}'", path.string(), c.name));
}

}  // namespace

Imf::Header exr_image_header(const Image& img, const ImageMetadata& meta) {
  Imf::Header header(img.width, img.height);
  if (img.display_width != 0) {
    header.displayWindow() = Imath::Box2i({0, 0}, {img.display_width - 1, img.display_height - 1});
    header.dataWindow() = Imath::Box2i({img.origin_x, img.origin_y},
                                       {img.origin_x + img.width - 1, img.origin_y + img.height - 1});
  }
  header.compression() = Imf::ZIP_COMPRESSION;
  // zlib's fastest level: a nimbus EXR carries its resume state (exr_state.cpp: 17 UINT channels beside
  // RGBA), and at OpenEXR's default level 4 compressing it took ~5 % of a 1-spp `mfs` render's CPU at
  // 512 x 512 (the r = 1 sphere: 2.30 -> 2.19 CPU s at level 1, the file 2 % larger).
  header.zipCompressionLevel() = 1;
  for (const char* c : {"R", "G", "B"}) header.channels().insert(c, Imf::Channel(Imf::FLOAT));
  if (!img.alpha.empty()) header.channels().insert("A", Imf::Channel(Imf::FLOAT));
  for (const ImageChannel& c : img.channels) header.channels().insert(c.name, Imf::Channel(Imf::FLOAT));
  for (const auto& [key, value] : meta) header.insert(key, Imf::StringAttribute(value));
  return header;
}

Imf::FrameBuffer exr_image_frame_buffer(const Image& img) {
  Imf::FrameBuffer fb;
  // OpenEXR addresses pixel (x, y) of the data window at base + x * xs + y * ys.
  const ptrdiff_t ox = img.display_width != 0 ? img.origin_x : 0,
                  oy = img.display_width != 0 ? img.origin_y : 0;
  const size_t xs = 3 * sizeof(float), ys = xs * img.width;
  char* base =
      reinterpret_cast<char*>(const_cast<float*>(img.rgb.data())) - ox * ptrdiff_t(xs) - oy * ptrdiff_t(ys);
  fb.insert("R", Imf::Slice(Imf::FLOAT, base, xs, ys));
  fb.insert("G", Imf::Slice(Imf::FLOAT, base + sizeof(float), xs, ys));
  fb.insert("B", Imf::Slice(Imf::FLOAT, base + 2 * sizeof(float), xs, ys));
  auto plane = [&](const std::string& name, const std::vector<float>& data) {
    char* p = reinterpret_cast<char*>(const_cast<float*>(data.data())) -
              (ox + oy * ptrdiff_t(img.width)) * ptrdiff_t(sizeof(float));
    fb.insert(name, Imf::Slice(Imf::FLOAT, p, sizeof(float), sizeof(float) * img.width));
  };
  if (!img.alpha.empty()) plane("A", img.alpha);
  for (const ImageChannel& c : img.channels) plane(c.name, c.data);
  return fb;
}

void write_exr(const fs::path& path, const Image& img, const ImageMetadata& meta, const FilmState* state) {
  check_image(path, img);
  if (state) return write_exr_with_state(path, img, meta, *state);
  atomic_write(path, [&](const fs::path& tmp) {
    Imf::OutputFile file(tmp.c_str(), exr_image_header(img, meta));
    file.setFrameBuffer(exr_image_frame_buffer(img));
    file.writePixels(img.height);
  });
}

Image read_exr(const fs::path& path, ImageMetadata* meta) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw Error(fmt::format("{}: no such file", path.string()));
  try {
    Imf::InputFile file(path.c_str());
    const Imath::Box2i dw = file.header().dataWindow();
    const int w = dw.max.x - dw.min.x + 1, h = dw.max.y - dw.min.y + 1;
    Image img(w, h);
    const auto& channels = file.header().channels();
    if (!channels.findChannel("R") && !channels.findChannel("G") && !channels.findChannel("B"))
      throw Error("no R, G or B channel");
    Imf::FrameBuffer fb;
    const size_t xs = 3 * sizeof(float), ys = xs * w;
    char* base = reinterpret_cast<char*>(img.rgb.data()) - (size_t(dw.min.x) * xs + size_t(dw.min.y) * ys);
    fb.insert("R", Imf::Slice(Imf::FLOAT, base, xs, ys, 1, 1, 0.0));
    fb.insert("G", Imf::Slice(Imf::FLOAT, base + sizeof(float), xs, ys, 1, 1, 0.0));
    fb.insert("B", Imf::Slice(Imf::FLOAT, base + 2 * sizeof(float), xs, ys, 1, 1, 0.0));
    if (channels.findChannel("A")) {
      img.alpha.assign(size_t(w) * h, 1.0f);
      char* a = reinterpret_cast<char*>(img.alpha.data()) -
                (size_t(dw.min.x) * sizeof(float) + size_t(dw.min.y) * sizeof(float) * w);
      fb.insert("A", Imf::Slice(Imf::FLOAT, a, sizeof(float), sizeof(float) * w, 1, 1, 1.0));
    }
    file.setFrameBuffer(fb);
    file.readPixels(dw.min.y, dw.max.y);
    const Imath::Box2i disp = file.header().displayWindow();
    if (dw != disp) {
      img.origin_x = dw.min.x - disp.min.x;
      img.origin_y = dw.min.y - disp.min.y;
      img.display_width = disp.max.x - disp.min.x + 1;
      img.display_height = disp.max.y - disp.min.y + 1;
    }
    if (meta) {
      meta->clear();
      for (auto it = file.header().begin(); it != file.header().end(); ++it) {
        if (const auto* s = dynamic_cast<const Imf::StringAttribute*>(&it.attribute()))
          meta->emplace_back(it.name(), s->value());
      }
    }
    return img;
  } catch (const Error& e) {
    throw Error(fmt::format("{}: {}", path.string(), e.what()));
  } catch (const std::exception& e) {
    throw Error(fmt::format("{}: cannot read EXR: {}", path.string(), e.what()));
  }
}

void write_png(const fs::path& path, const Image& img, double exposure_stops, bool with_alpha) {
  if (img.width <= 0 || img.height <= 0 || img.rgb.size() != size_t(img.width) * img.height * 3)
    throw Error(fmt::format("{}: cannot write an empty or malformed image", path.string()));
  const bool rgba = with_alpha && img.alpha.size() == size_t(img.width) * img.height;
  const int n = rgba ? 4 : 3;
  const double scale = std::exp2(exposure_stops);
  std::vector<uint8_t> pixels(size_t(img.width) * img.height * n);
  for (size_t p = 0; p < size_t(img.width) * img.height; ++p) {
    // A PNG's alpha is straight: the colour is divided by it (0 where nothing covers the pixel).
    const double a = rgba ? std::clamp(double(img.alpha[p]), 0.0, 1.0) : 1.0;
    for (int c = 0; c < 3; ++c) {
      const double v = rgba ? (a > 0.0 ? double(img.rgb[3 * p + c]) / a : 0.0) * scale
                            : double(img.rgb[3 * p + c]) * scale;
      pixels[n * p + c] = uint8_t(std::lround(255.0 * srgb_encode(std::isfinite(v) ? v : 0.0)));
    }
    if (rgba) pixels[n * p + 3] = uint8_t(std::lround(255.0 * (std::isfinite(a) ? a : 0.0)));
  }
  png_image png{};
  png.version = PNG_IMAGE_VERSION;
  png.width = png_uint_32(img.width);
  png.height = png_uint_32(img.height);
  png.format = rgba ? PNG_FORMAT_RGBA : PNG_FORMAT_RGB;
  png_alloc_size_t size = 0;
  if (!png_image_write_to_memory(&png, nullptr, &size, 0, pixels.data(), 0, nullptr))
    throw Error(fmt::format("{}: cannot encode PNG: {}", path.string(), png.message));
  std::string bytes(size, '\0');
  if (!png_image_write_to_memory(&png, bytes.data(), &size, 0, pixels.data(), 0, nullptr))
    throw Error(fmt::format("{}: cannot encode PNG: {}", path.string(), png.message));
  bytes.resize(size);
  atomic_write_bytes(path, bytes);
}

void write_image(const fs::path& path, const Image& img, const ImageMetadata& meta, double exposure_stops,
                 bool png_alpha, const FilmState* state) {
  std::string ext = path.extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".exr") return write_exr(path, img, meta, state);
  if (ext == ".png") return write_png(path, img, exposure_stops, png_alpha);
  throw Error(fmt::format("{}: unsupported output extension '{}' (use .exr or .png)", path.string(), ext));
}

}  // namespace nimbus
