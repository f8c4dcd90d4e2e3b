// Comparing a test image against a reference: the numbers nimbus reports for every approximation.
//
// Luminance Y = 0.2126 R + 0.7152 G + 0.0722 B. Both images are box-binned into k x k bins (partial
// bins at the right and bottom edges are averaged over the pixels they have). Then:
//   mean_rel_error     = (mean Y_a - mean Y_b) / mean Y_b over the whole image (the "whole-image mean error")
//   rel_rmse           = sqrt(mean over included bins of (Y_a - Y_b)^2) / (mean over included bins of Y_b)
//   mean_abs_rel_error = mean over included bins of |Y_a - Y_b| / Y_b
// A bin is included when Y_b >= min_reference * (mean Y_b over all bins) and Y_b > 0.
#pragma once

#include "nimbus/image.h"

namespace nimbus {

struct CompareOptions {
  int bin = 1;                 // k x k box binning before the per-bin metrics
  double min_reference = 0.0;  // fraction of the mean reference luminance below which bins are excluded
};

struct CompareResult {
  double mean_a[3] = {0, 0, 0}, mean_b[3] = {0, 0, 0};
  double mean_lum_a = 0.0, mean_lum_b = 0.0;
  double mean_rel_error = 0.0;
  double rel_rmse = 0.0;
  double mean_abs_rel_error = 0.0;
  double max_abs_rel_error = 0.0;
  int bins_used = 0, bins_total = 0;
};

// b is the reference. Throws nimbus::Error on a size mismatch or a bad bin size.
CompareResult compare_images(const Image& a, const Image& b, const CompareOptions& options = {});
// Signed relative error per bin, (Y_a - Y_b) / Y_b, mapped blue (a < b) - white - red (a > b) with
// full colour at +-max_rel; excluded bins grey; at full image size.
Image error_heatmap(const Image& a, const Image& b, const CompareOptions& options = {}, double max_rel = 0.5);
// The heatmap's colour (linear RGB) of a relative error e / max_rel, clamped to [-1, 1]: white at 0,
// pure red at +1, pure blue at -1.
void heatmap_colour(double e, float rgb[3]);

}  // namespace nimbus
