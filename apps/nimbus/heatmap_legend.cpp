// The heatmap legend (heatmap_legend.h).
#include "heatmap_legend.h"

#include <fmt/format.h>

#include <algorithm>
#include <string>

#include "nimbus/compare.h"

namespace nimbus::cli {

namespace {

// 3x5 glyphs, one row per entry, bit 2 = left column.
struct Glyph {
  char c;
  unsigned char rows[5];
};
constexpr Glyph kFont[] = {
    {'0', {7, 5, 5, 5, 7}}, {'1', {2, 6, 2, 2, 7}}, {'2', {7, 1, 7, 4, 7}}, {'3', {7, 1, 7, 1, 7}},
    {'4', {5, 5, 7, 1, 1}}, {'5', {7, 4, 7, 1, 7}}, {'6', {7, 4, 7, 5, 7}}, {'7', {7, 1, 1, 1, 1}},
    {'8', {7, 5, 7, 5, 7}}, {'9', {7, 5, 7, 1, 7}}, {'+', {0, 2, 7, 2, 0}}, {'-', {0, 0, 7, 0, 0}},
    {'.', {0, 0, 0, 0, 2}}, {'%', {5, 1, 2, 4, 5}}, {'e', {0, 7, 7, 4, 3}},
};

void fill(Image& img, int x0, int y0, int w, int h, const float rgb[3]) {
  for (int y = std::max(y0, 0); y < std::min(y0 + h, img.height); ++y)
    for (int x = std::max(x0, 0); x < std::min(x0 + w, img.width); ++x)
      std::copy(rgb, rgb + 3, img.pixel(x, y));
}

int text_width(const std::string& s, int scale) { return int(s.size()) * 4 * scale - scale; }

void draw_text(Image& img, int x, int y, const std::string& s, int scale) {
  const float white[3] = {1.0f, 1.0f, 1.0f};
  for (char c : s) {
    for (const Glyph& g : kFont)
      if (g.c == c)
        for (int r = 0; r < 5; ++r)
          for (int col = 0; col < 3; ++col)
            if (g.rows[r] & (4 >> col)) fill(img, x + col * scale, y + r * scale, scale, scale, white);
    x += 4 * scale;
  }
}

}  // namespace

Image with_heatmap_legend(const Image& heatmap, double max_rel) {
  const int W = std::max(heatmap.width, 64), s = std::clamp(W / 128, 1, 4), m = 2 * s;
  const int bar_h = 4 * s, tick_h = 2 * s, legend_h = m + bar_h + tick_h + s + 5 * s + m;
  Image out(W, heatmap.height + legend_h);  // black
  for (int y = 0; y < heatmap.height; ++y)
    std::copy(heatmap.pixel(0, y), heatmap.pixel(0, y) + 3 * heatmap.width, out.pixel(0, y));
  // The bar: the heatmap's colours from -max_rel (left) to +max_rel (right).
  const int x0 = m, x1 = W - m, y_bar = heatmap.height + m;
  for (int x = x0; x < x1; ++x) {
    float rgb[3];
    heatmap_colour(2.0 * (x - x0 + 0.5) / (x1 - x0) - 1.0, rgb);
    fill(out, x, y_bar, 1, bar_h, rgb);
  }
  // Ticks and labels at both ends and the middle.
  const std::string r = fmt::format("{:.3g}%", 100.0 * max_rel);
  const std::string labels[3] = {"-" + r, "0", "+" + r};
  const int ticks[3] = {x0, (x0 + x1) / 2, x1 - s};
  const float white[3] = {1.0f, 1.0f, 1.0f};
  for (int i = 0; i < 3; ++i) {
    fill(out, ticks[i], y_bar + bar_h, s, tick_h, white);
    const int w = text_width(labels[i], s);
    const int x = i == 0 ? x0 : i == 1 ? ticks[1] - w / 2 : x1 - w;
    draw_text(out, x, y_bar + bar_h + tick_h + s, labels[i], s);
  }
  return out;
}

}  // namespace nimbus::cli
