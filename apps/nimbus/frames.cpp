// Frame sequences (frames.h).
#include "frames.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <set>

#include "nimbus/error.h"

namespace nimbus::cli {

namespace {

constexpr long kMaxFrame = 9999999;
constexpr size_t kMaxFrames = 100000;

// A whole non-negative number, all of `s`.
bool parse_number(const std::string& s, long* out) {
  if (s.empty() || s.size() > 8 || !std::all_of(s.begin(), s.end(), [](char c) { return std::isdigit(c); }))
    return false;
  *out = std::stol(s);
  return *out <= kMaxFrame;
}

}  // namespace

std::vector<int> parse_frames(const std::string& text) {
  auto bad = [&](const std::string& why) {
    return Error(fmt::format(
        "--frames '{}': {} (expected a list like 1-240, 1-10x2, 1,3,5 or 1-4,10 of frames 0 to {})", text,
        why, kMaxFrame));
  };
  std::vector<int> frames;
  std::set<int> seen;
  size_t pos = 0;
  if (text.empty()) throw bad("empty");
  while (pos <= text.size()) {
    const size_t comma = std::min(text.find(',', pos), text.size());
    const std::string item = text.substr(pos, comma - pos);
    long a = 0, b = 0, step = 1;
    const size_t dash = item.find('-'), x = item.find('x');
    if (dash == std::string::npos) {
      if (!parse_number(item, &a)) throw bad(fmt::format("'{}' is not a frame number", item));
      b = a;
    } else {
      const std::string last =
          item.substr(dash + 1, x == std::string::npos ? std::string::npos : x - dash - 1);
      if (!parse_number(item.substr(0, dash), &a) || !parse_number(last, &b) ||
          (x != std::string::npos && (x < dash || !parse_number(item.substr(x + 1), &step))))
        throw bad(fmt::format("'{}' is not a range A-B or A-BxSTEP", item));
      if (a > b) throw bad(fmt::format("'{}' runs backwards", item));
      if (step < 1) throw bad(fmt::format("'{}': the step must be >= 1", item));
    }
    for (long f = a; f <= b; f += step) {
      if (!seen.insert(int(f)).second) throw bad(fmt::format("frame {} is named twice", f));
      if (frames.size() == kMaxFrames) throw bad(fmt::format("more than {} frames", kMaxFrames));
      frames.push_back(int(f));
    }
    pos = comma + 1;
  }
  return frames;
}

std::string substitute_frame(const std::string& text, int frame) {
  std::string out;
  for (size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '$' && i + 1 < text.size() && text[i + 1] == 'F') {
      int width = 0;
      if (i + 2 < text.size() && text[i + 2] >= '1' && text[i + 2] <= '9') width = text[i + 2] - '0';
      out += fmt::format("{:0{}d}", frame, std::max(width, 1));
      i += width > 0 ? 2 : 1;
    } else {
      out += text[i];
    }
  }
  return out;
}

bool has_frame_token(const std::string& text) { return text.find("$F") != std::string::npos; }

void substitute_frame(nlohmann::json& doc, int frame) {
  if (doc.is_string()) {
    doc = substitute_frame(doc.get<std::string>(), frame);
  } else if (doc.is_structured()) {
    for (auto& v : doc) substitute_frame(v, frame);
  }
}

}  // namespace nimbus::cli
