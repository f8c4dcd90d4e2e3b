// The resume state beside the image in an EXR. Part 0 is the image, as a one-part file has it (readers
// that take the first part, as most compositors and OpenImageIO do, see the same picture); part 1,
// "nimbus.resume", holds the film's double sums bit for bit as pairs of UINT channels (LAYER.C.lo and
// LAYER.C.hi, the low and high 32 bits of each double) and the sample counts (count), with the samples
// per pixel taken in the attribute nimbus/resume_spp.
#include "io/exr_state.h"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfInputPart.h>
#include <OpenEXR/ImfIntAttribute.h>
#include <OpenEXR/ImfMultiPartInputFile.h>
#include <OpenEXR/ImfMultiPartOutputFile.h>
#include <OpenEXR/ImfOutputPart.h>
#include <OpenEXR/ImfPartType.h>
#include <fmt/format.h>

#include <bit>
#include <cmath>
#include <map>

#include "io/atomic_file.h"
#include "nimbus/error.h"

namespace nimbus {

namespace fs = std::filesystem;

namespace {

static_assert(std::endian::native == std::endian::little, "the state's word order assumes little endian");

constexpr const char* kPartName = "nimbus.resume";
constexpr const char* kSppAttribute = "nimbus/resume_spp";

std::string channel_name(const FilmState::Layer& l, int c, const char* half) {
  return fmt::format("{}.{}.{}", l.name, c, half);
}

// Slices of the state's doubles and counts: the low and high words of sums[channels * pixel + c].
Imf::FrameBuffer state_frame_buffer(FilmState& st) {
  Imf::FrameBuffer fb;
  for (FilmState::Layer& l : st.layers) {
    const size_t xs = sizeof(double) * size_t(l.channels), ys = xs * size_t(st.width);
    for (int c = 0; c < l.channels; ++c) {
      char* base = reinterpret_cast<char*>(l.sums.data() + c);
      fb.insert(channel_name(l, c, "lo"), Imf::Slice(Imf::UINT, base, xs, ys));
      fb.insert(channel_name(l, c, "hi"), Imf::Slice(Imf::UINT, base + 4, xs, ys));
    }
  }
  fb.insert("count", Imf::Slice(Imf::UINT, reinterpret_cast<char*>(st.counts.data()), sizeof(uint32_t),
                                sizeof(uint32_t) * size_t(st.width)));
  return fb;
}

void check_state(const FilmState& st) {
  const size_t n = size_t(std::max(st.width, 0)) * size_t(std::max(st.height, 0));
  if (st.width <= 0 || st.height <= 0 || st.counts.size() != n || st.spp < 0)
    throw Error("malformed resume state");
  for (const FilmState::Layer& l : st.layers) {
    if (l.name.empty() || l.name.find('.') != std::string::npos || l.channels < 1 ||
        l.sums.size() != n * size_t(l.channels))
      throw Error(fmt::format("malformed resume state layer '{}'", l.name));
    for (double v : l.sums)
      if (!std::isfinite(v))
        throw Error(fmt::format("resume state layer '{}' holds a non-finite sum", l.name));
  }
  for (uint32_t c : st.counts)
    if (c != uint32_t(st.spp))
      throw Error(fmt::format("resume state: a pixel has {} samples, the image {} per pixel", c, st.spp));
}

}  // namespace

void write_exr_with_state(const fs::path& path, const Image& img, const ImageMetadata& meta,
                          const FilmState& state) {
  try {
    check_state(state);
  } catch (const Error& e) {
    throw Error(fmt::format("{}: {}", path.string(), e.what()));
  }
  if (state.width != img.width || state.height != img.height)
    throw Error(fmt::format("{}: the resume state's size differs from the image's", path.string()));
  FilmState st = state;  // the frame buffer points into it
  atomic_write(path, [&](const fs::path& tmp) {
    Imf::Header image = exr_image_header(img, meta);
    image.setName("rgba");
    image.setType(Imf::SCANLINEIMAGE);
    Imf::Header resume(st.width, st.height);
    resume.compression() = Imf::ZIP_COMPRESSION;
    resume.setName(kPartName);
    resume.setType(Imf::SCANLINEIMAGE);
    for (const FilmState::Layer& l : st.layers)
      for (int c = 0; c < l.channels; ++c)
        for (const char* half : {"lo", "hi"})
          resume.channels().insert(channel_name(l, c, half), Imf::Channel(Imf::UINT));
    resume.channels().insert("count", Imf::Channel(Imf::UINT));
    resume.insert(kSppAttribute, Imf::IntAttribute(st.spp));
    const Imf::Header headers[2] = {image, resume};
    Imf::MultiPartOutputFile file(tmp.c_str(), headers, 2);
    Imf::OutputPart part0(file, 0);
    part0.setFrameBuffer(exr_image_frame_buffer(img));
    part0.writePixels(img.height);
    Imf::OutputPart part1(file, 1);
    part1.setFrameBuffer(state_frame_buffer(st));
    part1.writePixels(st.height);
  });
}

namespace {

FilmState read_state(const fs::path& path) {
  Imf::MultiPartInputFile file(path.c_str());
  int index = -1;
  for (int i = 0; i < file.parts(); ++i)
    if (file.header(i).hasName() && file.header(i).name() == kPartName) index = i;
  if (index < 0) throw Error("no resume state (nimbus writes it in every EXR it renders)");
  const Imf::Header& h = file.header(index);
  const Imath::Box2i dw = h.dataWindow();
  const auto* spp = h.findTypedAttribute<Imf::IntAttribute>(kSppAttribute);
  if (!spp || dw.min.x != 0 || dw.min.y != 0) throw Error("malformed resume state");
  FilmState st;
  st.width = dw.max.x + 1;
  st.height = dw.max.y + 1;
  st.spp = spp->value();
  if (st.width > (1 << 16) || st.height > (1 << 16)) throw Error("malformed resume state");
  const size_t n = size_t(st.width) * size_t(st.height);
  std::map<std::string, int> channels;  // layer -> channels, from the LAYER.C.hi names
  for (auto it = h.channels().begin(); it != h.channels().end(); ++it) {
    if (it.channel().type != Imf::UINT)
      throw Error(fmt::format("resume channel '{}' is not UINT", it.name()));
    const std::string name = it.name();
    if (name == "count") continue;
    const size_t dot1 = name.find('.'), dot2 = name.rfind('.');
    if (dot1 == std::string::npos || dot1 == dot2) throw Error(fmt::format("resume channel '{}'", name));
    const int c = std::atoi(name.substr(dot1 + 1, dot2 - dot1 - 1).c_str());
    if (c < 0 || c > 64) throw Error(fmt::format("resume channel '{}'", name));
    int& k = channels[name.substr(0, dot1)];
    k = std::max(k, c + 1);
  }
  for (const auto& [name, k] : channels) st.layers.push_back({name, k, std::vector<double>(n * size_t(k))});
  st.counts.assign(n, 0);
  Imf::InputPart part(file, index);
  Imf::FrameBuffer fb = state_frame_buffer(st);
  for (auto it = fb.begin(); it != fb.end(); ++it)
    if (!h.channels().findChannel(it.name()))
      throw Error(fmt::format("resume channel '{}' missing", it.name()));
  part.setFrameBuffer(fb);
  part.readPixels(0, st.height - 1);
  check_state(st);
  return st;
}

}  // namespace

FilmState read_exr_state(const fs::path& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw Error(fmt::format("{}: no such file", path.string()));
  try {
    return read_state(path);
  } catch (const Error& e) {
    throw Error(fmt::format("{}: {}", path.string(), e.what()));
  } catch (const std::exception& e) {
    throw Error(fmt::format("{}: cannot read the resume state: {}", path.string(), e.what()));
  }
}

}  // namespace nimbus
