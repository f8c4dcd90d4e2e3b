// Merging renders of one frame (nimbus/merge.h). Each input is a data window (its crop) and a sample
// range [start, start + spp); the film states' fixed-point sums of every pixel are added. Integer sums
// add exactly, so tiles assemble and sample ranges add up to the render of all their samples bit for bit
// (render/film.h).
// The cells between the windows' edges are each covered by one set of inputs: the coverage is checked
// cell by cell, not pixel by pixel.
#include "nimbus/merge.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <optional>

#include "nimbus/error.h"
#include "nimbus/scene.h"
#include "render/film.h"
#include "render/film_layers.h"

namespace nimbus {

namespace {

struct Input {
  std::string file;
  Image image;
  ImageMetadata meta;
  FilmState state;
  int x0 = 0, y0 = 0;         // the data window's first pixel in the frame
  int width = 0, height = 0;  // the frame (display window)
  int start = 0;              // the first sample
  nlohmann::json scene, settings;
};

std::string meta_or(const ImageMetadata& meta, const std::string& key, const std::string& fallback) {
  for (const auto& [k, v] : meta)
    if (k == key) return v;
  return fallback;
}

nlohmann::json meta_json(const Input& in, const std::string& key) {
  const std::string text = meta_or(in.meta, key, "");
  if (text.empty()) throw Error(fmt::format("{}: no {} in the header (not a nimbus render?)", in.file, key));
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception&) {
    throw Error(fmt::format("{}: {}: not valid JSON", in.file, key));
  }
}

Input read_input(const std::filesystem::path& path) {
  Input in;
  in.file = path.string();
  in.image = read_exr(path, &in.meta);
  in.state = read_exr_state(path);
  in.x0 = in.image.origin_x;
  in.y0 = in.image.origin_y;
  in.width = in.image.display_width != 0 ? in.image.display_width : in.image.width;
  in.height = in.image.display_width != 0 ? in.image.display_height : in.image.height;
  if (in.x0 < 0 || in.y0 < 0 || in.x0 + in.image.width > in.width || in.y0 + in.image.height > in.height)
    throw Error(fmt::format("{}: the data window is not inside the display window", in.file));
  const std::string start = meta_or(in.meta, "nimbus/sample_start", "0");
  char extra = 0;
  if (std::sscanf(start.c_str(), "%d%c", &in.start, &extra) != 1 || in.start < 0)
    throw Error(fmt::format("{}: nimbus/sample_start '{}' is not a sample index", in.file, start));
  // What must agree between inputs: the scene and the integrator's settings but their spp.
  in.scene = meta_json(in, "nimbus/scene");
  in.settings = meta_json(in, "nimbus/integrator_settings");
  if (in.settings.is_object()) in.settings.erase("spp");
  if (in.scene.is_object() && in.scene.contains("integrator") && in.scene["integrator"].is_object())
    in.scene["integrator"].erase("spp");
  return in;
}

// Throws unless `in` renders the same frame as `first`, naming the file and the field.
void check_compatible(const Input& first, const Input& in) {
  auto differ = [&](const std::string& field, const std::string& a, const std::string& b) {
    throw Error(fmt::format("{}: {} differs from {}'s ({} vs {}): not renders of one frame", in.file, field,
                            first.file, b, a));
  };
  for (const char* key : {"nimbus/integrator", "nimbus/seed", "nimbus/max_events"}) {
    const std::string a = meta_or(first.meta, key, "(none)"), b = meta_or(in.meta, key, "(none)");
    if (a != b) differ(key, a, b);
  }
  if (first.settings != in.settings)
    differ("nimbus/integrator_settings", first.settings.dump(), in.settings.dump());
  if (first.scene != in.scene) {
    std::string field = "nimbus/scene";  // name the scene's first differing top-level field
    if (first.scene.is_object() && in.scene.is_object())
      for (const auto& [k, v] : first.scene.items())
        if (!in.scene.contains(k) || in.scene[k] != v) {
          field += " (" + k + ")";
          break;
        }
    throw Error(
        fmt::format("{}: {} differs from {}'s: not renders of one scene", in.file, field, first.file));
  }
  if (first.width != in.width || first.height != in.height)
    differ("image size (display window)", fmt::format("{}x{}", first.width, first.height),
           fmt::format("{}x{}", in.width, in.height));
  auto layers = [](const FilmState& s) {
    std::string out;
    for (const FilmState::Layer& l : s.layers)
      out += fmt::format("{}{}:{}/2^-{}", out.empty() ? "" : ",", l.name, l.channels, l.fraction_bits);
    return out;
  };
  if (layers(first.state) != layers(in.state))
    differ("film layers (resume state)", layers(first.state), layers(in.state));
}

// The film settings the header's scene names (for resolving the merged film into channels).
FilmSettings film_settings(const Input& in) {
  FilmSettings fs;
  if (!in.scene.contains("film")) return fs;
  try {
    const nlohmann::json& f = in.scene.at("film");
    fs.transparent = f.value("transparent", false);
    fs.layers = f.value("layers", std::vector<std::string>{});
  } catch (const nlohmann::json::exception&) {
    throw Error(fmt::format("{}: nimbus/scene: malformed film block", in.file));
  }
  return fs;
}

struct Window {
  int x0, y0, x1, y1;
};

// Checks that every cell of the window is covered by inputs with disjoint sample ranges that join into
// one range, the same everywhere; returns its [first, end).
std::pair<int, int> check_coverage(const std::vector<Input>& inputs, const Window& w) {
  std::vector<int> xs = {w.x0, w.x1}, ys = {w.y0, w.y1};
  for (const Input& in : inputs) {
    xs.insert(xs.end(), {in.x0, in.x0 + in.image.width});
    ys.insert(ys.end(), {in.y0, in.y0 + in.image.height});
  }
  for (auto* v : {&xs, &ys}) {
    std::sort(v->begin(), v->end());
    v->erase(std::unique(v->begin(), v->end()), v->end());
  }
  std::optional<std::pair<int, int>> range;
  for (size_t j = 0; j + 1 < ys.size(); ++j)
    for (size_t i = 0; i + 1 < xs.size(); ++i) {
      const int x = xs[i], y = ys[j];  // the cell's first pixel stands for the cell
      int end = -1, first = -1;
      std::string last_file;
      for (const Input& in : inputs) {  // sorted by start
        if (x < in.x0 || x >= in.x0 + in.image.width || y < in.y0 || y >= in.y0 + in.image.height) continue;
        if (end >= 0 && in.start != end)
          throw Error(fmt::format(
              "{}: samples {}..{} at pixel ({}, {}) {} those of {} (which end before sample {}): the "
              "sample ranges must be disjoint and adjacent",
              in.file, in.start, in.start + in.state.spp - 1, x, y,
              in.start < end ? "overlap" : "do not follow", last_file, end));
        if (first < 0) first = in.start;
        end = in.start + in.state.spp;
        last_file = in.file;
      }
      if (first < 0)
        throw Error(
            fmt::format("pixel ({}, {}) is in no input (the inputs' windows leave a gap in {},{},{},{})", x,
                        y, w.x0, w.y0, w.x1, w.y1));
      if (range && *range != std::pair{first, end})
        throw Error(
            fmt::format("pixel ({}, {}) has samples {}..{}, pixel ({}, {}) {}..{}: every pixel needs "
                        "the same sample range",
                        x, y, first, end - 1, xs[0], ys[0], range->first, range->second - 1));
      range = std::pair{first, end};
    }
  return *range;
}

// The header of the merged image: the first input's, with the merged spp, sample range, window and mean
// sample count per pixel (mfs's outline pixels take more than the spp).
ImageMetadata merged_metadata(const Input& first, size_t inputs, int start, int spp, double spp_mean,
                              const Window& w, bool whole, double seconds) {
  nlohmann::json scene = meta_json(first, "nimbus/scene");
  nlohmann::json settings = meta_json(first, "nimbus/integrator_settings");
  settings["spp"] = spp;
  if (scene.is_object()) scene["integrator"] = settings;
  ImageMetadata meta;
  for (const auto& [k, v] : first.meta) {
    if (k.rfind("nimbus/", 0) != 0 || k == "nimbus/region" || k == "nimbus/resume_spp") continue;
    std::string value = v;
    if (k == "nimbus/spp" || k == "nimbus/spp_requested") value = std::to_string(spp);
    if (k == "nimbus/sample_start") value = std::to_string(start);
    if (k == "nimbus/integrator_settings") value = settings.dump();
    if (k == "nimbus/scene") value = scene.dump();
    if (k == "nimbus/partial" || k == "nimbus/time_limited") value = "false";
    if (k == "nimbus/render_seconds") value = fmt::format("{:.3f}", seconds);
    if (k == "nimbus/spp_mean") value = fmt::format("{:.3f}", spp_mean);
    meta.emplace_back(k, value);
  }
  if (!whole) meta.emplace_back("nimbus/region", fmt::format("{},{},{},{}", w.x0, w.y0, w.x1, w.y1));
  meta.emplace_back("nimbus/merged_inputs", std::to_string(inputs));
  return meta;
}

}  // namespace

MergeResult merge_renders(const std::vector<std::filesystem::path>& files) {
  if (files.empty()) throw Error("merge: no input files");
  std::vector<Input> inputs;
  for (const auto& f : files) {
    inputs.push_back(read_input(f));
    check_compatible(inputs.front(), inputs.back());
  }
  std::stable_sort(inputs.begin(), inputs.end(),
                   [](const Input& a, const Input& b) { return a.start < b.start; });
  Window w{inputs[0].x0, inputs[0].y0, inputs[0].x0 + inputs[0].image.width,
           inputs[0].y0 + inputs[0].image.height};
  for (const Input& in : inputs)
    w = {std::min(w.x0, in.x0), std::min(w.y0, in.y0), std::max(w.x1, in.x0 + in.image.width),
         std::max(w.y1, in.y0 + in.image.height)};
  const auto [start, end] = check_coverage(inputs, w);

  // The sums, pixel by pixel (exact: any order gives the same).
  const int W = w.x1 - w.x0, H = w.y1 - w.y0;
  Film film(W, H);
  const FilmLayers layers(film, film_settings(inputs[0]), false);
  FilmState st = film.state(end - start);
  double seconds = 0.0;
  for (const Input& in : inputs) {
    seconds += std::atof(meta_or(in.meta, "nimbus/render_seconds", "0").c_str());
    std::vector<const FilmState::Layer*> from;  // the input's layer for each of st's
    for (const FilmState::Layer& out : st.layers) {
      const auto it = std::find_if(in.state.layers.begin(), in.state.layers.end(),
                                   [&](const FilmState::Layer& l) { return l.name == out.name; });
      if (it == in.state.layers.end() || it->channels != out.channels ||
          it->fraction_bits != out.fraction_bits)
        throw Error(
            fmt::format("{}: its film state has no layer '{}' of {} channels on a grid of 2^-{} (the "
                        "scene's film)",
                        in.file, out.name, out.channels, out.fraction_bits));
      from.push_back(&*it);
    }
    for (int y = 0; y < in.image.height; ++y)
      for (int x = 0; x < in.image.width; ++x) {
        const size_t src = size_t(y) * size_t(in.image.width) + size_t(x);
        const size_t dst = size_t(in.y0 + y - w.y0) * size_t(W) + size_t(in.x0 + x - w.x0);
        for (size_t l = 0; l < st.layers.size(); ++l) {
          const size_t k = size_t(st.layers[l].channels);
          FilmSum* out = &st.layers[l].sums[k * dst];
          const FilmSum* add = &from[l]->sums[k * src];
          for (size_t c = 0; c < k; ++c)  // sums that would leave 128 bits are refused
            if (__builtin_add_overflow(out[c], add[c], &out[c]))
              throw Error(fmt::format("{}: the film sums overflow at pixel ({}, {})", in.file, x, y));
        }
        if (__builtin_add_overflow(st.counts[dst], in.state.counts[src], &st.counts[dst]))
          throw Error(fmt::format("{}: the sample counts overflow at pixel ({}, {})", in.file, x, y));
      }
  }
  film.restore(st);

  MergeResult r;
  r.image = layers.resolve(film);
  const bool whole = w.x0 == 0 && w.y0 == 0 && w.x1 == inputs[0].width && w.y1 == inputs[0].height;
  if (!whole) {
    r.image.origin_x = w.x0;
    r.image.origin_y = w.y0;
    r.image.display_width = inputs[0].width;
    r.image.display_height = inputs[0].height;
  }
  r.state = std::move(st);
  r.sample_start = start;
  double count_sum = 0.0;
  for (uint32_t c : r.state.counts) count_sum += c;
  r.metadata = merged_metadata(inputs[0], inputs.size(), start, end - start,
                               count_sum / double(r.state.counts.size()), w, whole, seconds);
  return r;
}

}  // namespace nimbus
