// Deep pixels from camera-ray segments: the segments of all of a pixel's samples (integrators append
// them to CameraSample::deep) are binned in depth and merged into at most N deep samples, each with its
// own premultiplied colour and alpha, so that compositing them front to back ("over") gives the pixel's
// flat RGBA on a transparent film.
#pragma once

#include <vector>

#include "integrators/integrator.h"
#include "nimbus/image.h"

namespace nimbus {

// `segments`: every sample's segments, each to count with `weight` (1 / samples); max_samples >= 1.
// The depth range of the segments is cut into 4 max_samples equal bins (a segment spread over the bins
// it covers in proportion to length); the non-empty bins are merged front to back into at most
// max_samples groups of about equal alpha. Each group's absolute colour C and alpha A (its share of the
// pixel) become the deep sample's own c = C / (1 - A_front), a = A / (1 - A_front), A_front the alpha of
// the groups in front; once the front is opaque (1 - A_front < 1e-9) the rest is left out.
void merge_deep_segments(const std::vector<DeepSegment>& segments, double weight, int max_samples,
                         std::vector<DeepSample>* out);

}  // namespace nimbus
