// Images: linear float RGB (and optionally alpha and named layers) in memory, written as EXR (float
// channels, ZIP) or as an sRGB PNG preview; deep images (per-pixel lists of samples in depth) written as
// deep scanline EXR. Every write is atomic (temporary file in the same folder, then rename): an existing
// file is never replaced by a half-written one, and a failed write leaves it untouched.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace nimbus {

// One further EXR channel: its full name ("Z", "direct.R", ...) and one float per pixel, row-major.
struct ImageChannel {
  std::string name;
  std::vector<float> data;
};

struct Image {  // linear RGB, row-major, row 0 = top, 3 floats per pixel
  int width = 0, height = 0;
  std::vector<float> rgb;
  // Coverage, one float per pixel, or empty (an RGB image). With alpha, rgb is premultiplied by it.
  std::vector<float> alpha;
  // Further channels for the EXR (the compositing layers); PNG output ignores them.
  std::vector<ImageChannel> channels;
  // A crop of a larger image (render --region): its pixels start at (origin_x, origin_y) of a display
  // window of display_width x display_height; written to EXR as that data window inside that display
  // window. display_width == 0: the image is its whole display window (origin 0).
  int origin_x = 0, origin_y = 0, display_width = 0, display_height = 0;
  Image() = default;
  Image(int w, int h);  // zero-filled; throws nimbus::Error for sizes <= 0 or over 2^28 pixels
  float* pixel(int x, int y) { return &rgb[(size_t(y) * width + x) * 3]; }
  const float* pixel(int x, int y) const { return &rgb[(size_t(y) * width + x) * 3]; }
};

// A film sum: a signed 128-bit fixed-point number, its value sum * 2^-fraction_bits. Every sample enters
// the sum rounded once to that grid (src/render/film.h), so sums add exactly: associatively, in any order.
__extension__ typedef __int128 FilmSum;
// A sample enters a film sum within +-2^kFilmSampleBits grid steps; a sum saturates at +-(2^127 - 1).
inline constexpr int kFilmSampleBits = 126;

// A render's exact accumulation state: per film layer the fixed-point sums of its samples (`channels` per
// pixel, row-major, on a grid of 2^-fraction_bits), and each pixel's sample count. Written beside the
// image in the EXR (UINT channels nimbus_resume_*) so that `render --resume` continues it and `nimbus
// merge` adds sample ranges bit for bit (docs/cli.md).
struct FilmState {
  struct Layer {
    std::string name;
    int channels = 0;
    int fraction_bits = 0;
    std::vector<FilmSum> sums;
  };
  int width = 0, height = 0;
  int spp = 0;  // samples per pixel taken
  std::vector<Layer> layers;
  std::vector<uint32_t> counts;
};

// String attributes of an EXR header, e.g. {"nimbus/scene", "{...}"}.
using ImageMetadata = std::vector<std::pair<std::string, std::string>>;

// R, G, B, then A when the image has alpha, then its further channels (OpenEXR stores them sorted by name).
// With a film state: its channels too (io/exr_state.cpp).
void write_exr(const std::filesystem::path& path, const Image& img, const ImageMetadata& meta = {},
               const FilmState* state = nullptr);
// Reads R, G, B (any pixel type; a missing channel reads as 0), A when present, and the string
// attributes; further channels are not read. The image is the data window; a data window other than the
// display window sets the origin and display size.
Image read_exr(const std::filesystem::path& path, ImageMetadata* meta = nullptr);
// The film state of an EXR written with one; throws nimbus::Error (naming the file) when it has none or
// the state is malformed.
FilmState read_exr_state(const std::filesystem::path& path);
// 8-bit sRGB (the sRGB transfer function, not a 2.2 gamma) of the RGB scaled by 2^exposure (premultiplied
// colour: the image over black); values are clamped to [0, 1] and non-finite values written as 0. With
// with_alpha and an image with alpha: an RGBA PNG with straight (unpremultiplied) colour, for viewers
// and web pages that composite it themselves.
void write_png(const std::filesystem::path& path, const Image& img, double exposure_stops = 0.0,
               bool with_alpha = false);
// By extension: .exr or .png (any case); anything else is an error.
void write_image(const std::filesystem::path& path, const Image& img, const ImageMetadata& meta,
                 double exposure_stops, bool png_alpha = false, const FilmState* state = nullptr);

// sRGB encoding of a linear value in [0, 1] (IEC 61966-2-1).
double srgb_encode(double linear);

// One deep sample: the depth range [z, z_back] along the camera ray and its own premultiplied colour
// and alpha (an EXR deep sample: composited front to back with "over").
struct DeepSample {
  float z = 0.0f, z_back = 0.0f;
  float r = 0.0f, g = 0.0f, b = 0.0f, a = 0.0f;
};
// Per pixel (row-major, row 0 = top) a list of deep samples sorted front to back:
// samples[offsets[i] .. offsets[i + 1]) belong to pixel i.
struct DeepImage {
  int width = 0, height = 0;
  std::vector<uint64_t> offsets;  // width * height + 1 entries
  std::vector<DeepSample> samples;
};

// A deep scanline EXR with channels Z, ZBack, R, G, B, A (float), ZIP-compressed.
void write_deep_exr(const std::filesystem::path& path, const DeepImage& img, const ImageMetadata& meta = {});
DeepImage read_deep_exr(const std::filesystem::path& path);
// Composites each pixel's samples front to back ("over"): the flat premultiplied RGBA.
Image flatten(const DeepImage& img);

}  // namespace nimbus
