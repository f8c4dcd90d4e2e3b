// Merging renders of one frame (nimbus merge): crops (render --region) assemble into the frame, renders
// of disjoint sample ranges (render --samples START:COUNT) add up to the render of all their samples.
// Works on the film states the EXRs carry (per-pixel double sums), not on their float pixels.
#pragma once

#include <filesystem>
#include <vector>

#include "nimbus/image.h"

namespace nimbus {

struct MergeResult {
  Image image;             // the bounding box of the inputs' windows (a crop unless it is the frame)
  FilmState state;         // its film state, to write beside it (and to resume or merge again)
  ImageMetadata metadata;  // the first input's header, with the merged spp, sample range and window
  int sample_start = 0;    // the samples every pixel holds: [sample_start, sample_start + state.spp)
};

// Reads and merges nimbus EXRs (each with its film state). Every pixel of the output (the bounding box
// of the inputs' data windows) must be covered by inputs whose sample ranges are disjoint and together
// one range, the same for every pixel. Sums are added in the order of the ranges' first samples, pixel
// by pixel (docs/cli.md: what is bit-identical). The inputs must be renders of the same scene with the
// same settings but spp, the same integrator, seed, image size and film layers: otherwise nimbus::Error
// naming the file and the header field.
MergeResult merge_renders(const std::vector<std::filesystem::path>& files);

}  // namespace nimbus
