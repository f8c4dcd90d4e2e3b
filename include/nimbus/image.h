// Images: linear float RGB in memory, written as EXR (float channels, ZIP) or as an sRGB PNG preview.
// Every write is atomic (temporary file in the same folder, then rename): an existing file is never
// replaced by a half-written one, and a failed write leaves it untouched.
#pragma once

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace nimbus {

struct Image {  // linear RGB, row-major, row 0 = top, 3 floats per pixel
  int width = 0, height = 0;
  std::vector<float> rgb;
  Image() = default;
  Image(int w, int h);  // zero-filled; throws nimbus::Error for sizes <= 0 or over 2^28 pixels
  float* pixel(int x, int y) { return &rgb[(size_t(y) * width + x) * 3]; }
  const float* pixel(int x, int y) const { return &rgb[(size_t(y) * width + x) * 3]; }
};

// String attributes of an EXR header, e.g. {"nimbus/scene", "{...}"}.
using ImageMetadata = std::vector<std::pair<std::string, std::string>>;

void write_exr(const std::filesystem::path& path, const Image& img, const ImageMetadata& meta = {});
// Reads R, G, B (any pixel type; a missing channel reads as 0) and the string attributes.
Image read_exr(const std::filesystem::path& path, ImageMetadata* meta = nullptr);
// 8-bit sRGB (the sRGB transfer function, not a 2.2 gamma) of the image scaled by 2^exposure;
// values are clamped to [0, 1] and non-finite values written as 0.
void write_png(const std::filesystem::path& path, const Image& img, double exposure_stops = 0.0);
// By extension: .exr or .png (any case); anything else is an error.
void write_image(const std::filesystem::path& path, const Image& img, const ImageMetadata& meta,
                 double exposure_stops);

// sRGB encoding of a linear value in [0, 1] (IEC 61966-2-1).
double srgb_encode(double linear);

}  // namespace nimbus
