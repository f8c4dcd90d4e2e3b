// The resume state beside the image in an EXR: further channels of the one part, named
// nimbus_resume_LAYER_C_w0 .. _w3 (the four 32-bit words, least significant first, of each of the film's
// 128-bit fixed-point sums, as UINT, so kept bit for bit) and nimbus_resume_count (the samples per
// pixel), with the spp in the header attribute nimbus/resume_spp and each layer's grid (its sums are in
// units of 2^-bits) in nimbus/resume_bits_LAYER. No dot in the names: readers that group layer.channel
// names (Blender, Nuke) keep the image a plain RGBA one. (Blender 3.4 loads a second EXR part as an empty
// image.) States of nimbus before the fixed-point film (double sums in _lo and _hi words) are refused.
#include "io/exr_state.h"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfIntAttribute.h>
#include <OpenEXR/ImfOutputFile.h>
#include <fmt/format.h>

#include <bit>
#include <cmath>
#include <map>

#include "io/atomic_file.h"
#include "nimbus/error.h"
#include "nimbus/scene.h"

namespace nimbus {

namespace fs = std::filesystem;

namespace {

static_assert(std::endian::native == std::endian::little, "the state's word order assumes little endian");

constexpr const char* kPrefix = "nimbus_resume_";
constexpr const char* kSppAttribute = "nimbus/resume_spp";
constexpr const char* kBitsAttribute = "nimbus/resume_bits_";  // + the layer's name
constexpr int kWords = int(sizeof(FilmSum) / sizeof(uint32_t));

std::string channel_name(const FilmState::Layer& l, int c, int word) {
  return fmt::format("{}{}_{}_w{}", kPrefix, l.name, c, word);
}

// Slices of the state's sums and counts: the four words of sums[channels * pixel + c], for a data window
// that starts at (ox, oy).
Imf::FrameBuffer state_frame_buffer(FilmState& st, ptrdiff_t ox, ptrdiff_t oy) {
  Imf::FrameBuffer fb;
  for (FilmState::Layer& l : st.layers) {
    const size_t xs = sizeof(FilmSum) * size_t(l.channels), ys = xs * size_t(st.width);
    for (int c = 0; c < l.channels; ++c) {
      char* base = reinterpret_cast<char*>(l.sums.data() + c) - ox * ptrdiff_t(xs) - oy * ptrdiff_t(ys);
      for (int w = 0; w < kWords; ++w)
        fb.insert(channel_name(l, c, w), Imf::Slice(Imf::UINT, base + 4 * w, xs, ys));
    }
  }
  const ptrdiff_t first = ox + oy * ptrdiff_t(st.width);
  fb.insert(std::string(kPrefix) + "count",
            Imf::Slice(Imf::UINT, reinterpret_cast<char*>(st.counts.data() - first), sizeof(uint32_t),
                       sizeof(uint32_t) * size_t(st.width)));
  return fb;
}

void check_state(const FilmState& st) {
  const size_t n = size_t(std::max(st.width, 0)) * size_t(std::max(st.height, 0));
  if (st.width <= 0 || st.height <= 0 || st.counts.size() != n || st.spp < 0)
    throw Error("malformed resume state");
  for (const FilmState::Layer& l : st.layers) {
    if (l.name.empty() || l.name.find_first_of("._") != std::string::npos || l.channels < 1 ||
        l.sums.size() != n * size_t(l.channels))
      throw Error(fmt::format("malformed resume state layer '{}'", l.name));
    if (l.fraction_bits < 0 || l.fraction_bits > 120)
      throw Error(fmt::format("resume state layer '{}': a grid of 2^-{}", l.name, l.fraction_bits));
  }
  // Adaptive sampling leaves pixels with fewer samples than the image's spp (the most any pixel took);
  // outline pixels (mfs's edge_samples) take up to kMaxEdgeSamples per pixel sample.
  if (st.spp > kMaxSpp) throw Error(fmt::format("resume state: {} spp, more than {}", st.spp, kMaxSpp));
  for (uint32_t c : st.counts)
    if (uint64_t(c) > uint64_t(st.spp) * kMaxEdgeSamples)
      throw Error(fmt::format("resume state: a pixel has {} samples, more than {} x the image's {} spp", c,
                              kMaxEdgeSamples, st.spp));
  // Any 128-bit sum is possible (the film saturates at +-(2^127 - 1)); merges add with overflow checks.
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
    Imf::Header header = exr_image_header(img, meta);
    for (const FilmState::Layer& l : st.layers)
      for (int c = 0; c < l.channels; ++c)
        for (int w = 0; w < kWords; ++w)
          header.channels().insert(channel_name(l, c, w), Imf::Channel(Imf::UINT));
    header.channels().insert(std::string(kPrefix) + "count", Imf::Channel(Imf::UINT));
    header.insert(kSppAttribute, Imf::IntAttribute(st.spp));
    for (const FilmState::Layer& l : st.layers)
      header.insert(kBitsAttribute + l.name, Imf::IntAttribute(l.fraction_bits));
    Imf::FrameBuffer fb = exr_image_frame_buffer(img);
    const Imath::Box2i dw = header.dataWindow();
    const Imf::FrameBuffer state = state_frame_buffer(st, dw.min.x, dw.min.y);
    for (auto it = state.begin(); it != state.end(); ++it) fb.insert(it.name(), it.slice());
    Imf::OutputFile file(tmp.c_str(), header);
    file.setFrameBuffer(fb);
    file.writePixels(img.height);
  });
}

namespace {

FilmState read_state(const fs::path& path) {
  Imf::InputFile file(path.c_str());
  const Imf::Header& h = file.header();
  const Imath::Box2i dw = h.dataWindow();
  const auto* spp = h.findTypedAttribute<Imf::IntAttribute>(kSppAttribute);
  if (!spp) throw Error("no resume state (nimbus writes one in every EXR render)");
  FilmState st;  // the data window's pixels (a crop: render --region)
  st.width = dw.max.x - dw.min.x + 1;
  st.height = dw.max.y - dw.min.y + 1;
  st.spp = spp->value();
  if (st.width < 1 || st.height < 1 || st.width > (1 << 16) || st.height > (1 << 16) ||
      size_t(st.width) * size_t(st.height) > (size_t(1) << 28))
    throw Error("malformed resume state (image size)");
  const size_t n = size_t(st.width) * size_t(st.height);
  std::map<std::string, int> channels;  // layer -> channels, from the PREFIX_LAYER_C_wN names
  const std::string prefix = kPrefix;
  for (auto it = h.channels().begin(); it != h.channels().end(); ++it) {
    const std::string full = it.name();
    if (full.compare(0, prefix.size(), prefix) != 0) continue;
    if (it.channel().type != Imf::UINT) throw Error(fmt::format("resume channel '{}' is not UINT", full));
    const std::string name = full.substr(prefix.size());
    if (name == "count") continue;
    const size_t dot1 = name.find('_'), dot2 = name.rfind('_');
    if (dot1 == std::string::npos || dot1 == dot2) throw Error(fmt::format("resume channel '{}'", full));
    const std::string word = name.substr(dot2 + 1);
    if (word == "lo" || word == "hi")
      throw Error(
          "the film state of an older nimbus (double sums, before the exact fixed-point film): it cannot "
          "be resumed or merged; render it again");
    if (word.size() != 2 || word[0] != 'w' || word[1] < '0' || word[1] >= char('0' + kWords))
      throw Error(fmt::format("resume channel '{}'", full));
    const int c = std::atoi(name.substr(dot1 + 1, dot2 - dot1 - 1).c_str());
    if (c < 0 || c > 64) throw Error(fmt::format("resume channel '{}'", full));
    int& k = channels[name.substr(0, dot1)];
    k = std::max(k, c + 1);
  }
  for (const auto& [name, k] : channels) {
    const auto* bits = h.findTypedAttribute<Imf::IntAttribute>(kBitsAttribute + name);
    if (!bits) throw Error(fmt::format("no {}{} (the grid of the layer's sums)", kBitsAttribute, name));
    st.layers.push_back({name, k, bits->value(), std::vector<FilmSum>(n * size_t(k))});
  }
  st.counts.assign(n, 0);
  Imf::FrameBuffer fb = state_frame_buffer(st, dw.min.x, dw.min.y);
  for (auto it = fb.begin(); it != fb.end(); ++it)
    if (!h.channels().findChannel(it.name()))
      throw Error(fmt::format("resume channel '{}' missing", it.name()));
  file.setFrameBuffer(fb);
  file.readPixels(dw.min.y, dw.max.y);
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
