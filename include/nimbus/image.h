// TEMPORARY STUB (replaced by the img branch).
#pragma once
#include <filesystem>
#include <string>
#include <utility>
#include <vector>
namespace nimbus {
struct Image {
  int width = 0, height = 0;
  std::vector<float> rgb;
  Image() = default;
  Image(int w, int h) : width(w), height(h), rgb(size_t(w) * h * 3, 0.0f) {}
  float* pixel(int x, int y) { return &rgb[(size_t(y) * width + x) * 3]; }
  const float* pixel(int x, int y) const { return &rgb[(size_t(y) * width + x) * 3]; }
};
using ImageMetadata = std::vector<std::pair<std::string, std::string>>;
}  // namespace nimbus
namespace nimbus {
void write_image(const std::filesystem::path& path, const Image& img, const ImageMetadata& meta, double exposure_stops);
}
