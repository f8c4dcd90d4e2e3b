// The `compare --heatmap` legend: a colour bar under the heatmap with its scale written at both ends
// and the middle (-R %, 0, +R %, R = --heatmap-range), drawn with a built-in 3x5 pixel font.
#pragma once

#include "nimbus/image.h"

namespace nimbus::cli {

// The heatmap on top (padded with black to at least 64 pixels wide), the legend below it on black.
Image with_heatmap_legend(const Image& heatmap, double max_rel);

}  // namespace nimbus::cli
