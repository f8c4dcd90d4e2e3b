// The film state in an EXR (nimbus/image.h: FilmState): UINT channels nimbus_resume_* beside the image.
#pragma once

#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>

#include <filesystem>

#include "nimbus/image.h"

namespace nimbus {

// The image part's header and frame buffer (io/image.cpp), shared by the one- and two-part writers.
Imf::Header exr_image_header(const Image& img, const ImageMetadata& meta);
Imf::FrameBuffer exr_image_frame_buffer(const Image& img);

// Writes the image (as write_exr) and the state's channels atomically; `img` is checked already.
void write_exr_with_state(const std::filesystem::path& path, const Image& img, const ImageMetadata& meta,
                          const FilmState& state);

}  // namespace nimbus
