// Parsers of the render command's ranges (ranges.h).
#include "ranges.h"

#include <fmt/format.h>

#include <cstdio>

#include "nimbus/error.h"
#include "nimbus/scene.h"

namespace nimbus::cli {

Region parse_region(const std::string& text, const std::string& what) {
  long long v[4] = {-1, -1, -1, -1};
  char c[3] = {0, 0, 0}, extra = 0;
  const int n = std::sscanf(text.c_str(), "%lld%c%lld%c%lld%c%lld%c", &v[0], &c[0], &v[1], &c[1], &v[2],
                            &c[2], &v[3], &extra);
  const bool ok = n == 7 && c[0] == ',' && c[1] == ',' && c[2] == ',' && v[0] >= 0 && v[1] >= 0 &&
                  v[0] < v[2] && v[1] < v[3] && v[2] <= (1 << 16) && v[3] <= (1 << 16);
  if (!ok)
    throw Error(fmt::format(
        "{} '{}': expected x0,y0,x1,y1 in pixels with 0 <= x0 < x1 and 0 <= y0 < y1 (half-open: the window "
        "holds the pixels x0 <= x < x1, y0 <= y < y1)",
        what, text));
  return {int(v[0]), int(v[1]), int(v[2]), int(v[3])};
}

std::pair<int, int> parse_samples(const std::string& text) {
  long long start = -1, count = -1;
  char colon = 0, extra = 0;
  if (std::sscanf(text.c_str(), "%lld%c%lld%c", &start, &colon, &count, &extra) != 3 || colon != ':' ||
      start < 0 || count < 1 || start + count > kMaxSpp)
    throw Error(fmt::format(
        "--samples '{}': expected START:COUNT with START >= 0, COUNT >= 1 and START + COUNT <= {}", text,
        kMaxSpp));
  return {int(start), int(count)};
}

}  // namespace nimbus::cli
