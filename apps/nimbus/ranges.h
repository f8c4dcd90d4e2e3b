// Parsers of the render command's ranges: --region x0,y0,x1,y1 and --samples START:COUNT.
#pragma once

#include <string>
#include <utility>

#include "nimbus/render.h"

namespace nimbus::cli {

// "x0,y0,x1,y1" (integers, half-open: nimbus/render.h Region); errors name `what`. Checks only the form
// and x0 < x1, y0 < y1: the image size is checked against the scene.
Region parse_region(const std::string& text, const std::string& what);

// "START:COUNT" with START >= 0, COUNT >= 1, START + COUNT <= kMaxSpp: {START, COUNT}.
std::pair<int, int> parse_samples(const std::string& text);

}  // namespace nimbus::cli
