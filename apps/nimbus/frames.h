// Frame sequences (render --frames): frame lists such as "1-240", "1-10x2", "1,3,5" or "1-4,10", and the
// $F / $F4 frame tokens in file names.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace nimbus::cli {

// The frames of a list: comma-separated items N, A-B (A <= B, both included) or A-BxS (every S-th frame
// from A up to B). Frames are integers 0 .. 9999999, at most 100000 of them, none twice; the order is
// the list's. Throws nimbus::Error naming --frames otherwise.
std::vector<int> parse_frames(const std::string& text);

// `text` with every $F replaced by the frame number and every $FN (N = 1..9) by the number zero-padded to
// N digits ("cloud.$F4.vdb" at frame 7: "cloud.0007.vdb").
std::string substitute_frame(const std::string& text, int frame);
bool has_frame_token(const std::string& text);

// Every string value of a JSON document (file names and all), frame tokens replaced.
void substitute_frame(nlohmann::json& doc, int frame);

}  // namespace nimbus::cli
