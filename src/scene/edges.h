// The pixels a hard outline crosses: the silhouettes of constant-density spheres and boxes (media whose
// density jumps from 0 to 1 at their surface) and of opaque surfaces. At a few samples per pixel such a
// pixel's value is mostly which side of the outline its samples fell on: on a backlit dense sphere the
// thin bright rim makes those pixels most of `mfs`'s error (docs/benchmarks.md, "Samples at the
// outlines"). The driver gives them more samples (Integrator::edge_samples).
#pragma once

#include <cstdint>
#include <vector>

#include "nimbus/render.h"
#include "scene/context.h"

namespace nimbus {

enum class PixelEdge : uint8_t {
  none = 0,
  beside = 1,  // one of the eight pixels around an outline pixel
  outline = 2  // an outline crosses the pixel: the rays through its four corners do not all see the same
               // surface and the same set of sphere and box media in front of it
};

// Per pixel of `window` (row by row): its class. Pixels beside an outline pixel outside the window count,
// so that a window's classes are those of the whole image.
std::vector<PixelEdge> edge_pixels(const SceneContext& ctx, const Region& window);

}  // namespace nimbus
