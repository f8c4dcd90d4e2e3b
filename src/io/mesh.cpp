// OBJ meshes (io/mesh.h).
#include "io/mesh.h"

#include <fmt/format.h>
#include <tiny_obj_loader.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

#include "nimbus/error.h"

namespace nimbus {

namespace {

// A field of the file for a message: at most 32 characters, unprintable bytes as '?'.
std::string quoted(std::string_view field) {
  std::string q(field.substr(0, 32));
  for (char& ch : q)
    if (ch < 0x20 || ch > 0x7e) ch = '?';
  return "'" + q + (field.size() > 32 ? "...'" : "'");
}

// tinyobjloader's number parser accumulates a decimal exponent in an int, checked one digit too late:
// an exponent of 2147483648 overflows it (undefined behaviour, found by fuzz/mesh_fuzz). A number whose
// exponent has 10 or more digits (leading zeros aside) is refused before it gets there.
void check_exponents(std::string_view s, size_t line, const std::string& name) {
  while (!s.empty()) {
    s.remove_prefix(std::min(s.find_first_not_of(" \t"), s.size()));
    const std::string_view field = s.substr(0, s.find_first_of(" \t"));
    s.remove_prefix(field.size());
    size_t e = field.find_first_of("eE");
    if (e == std::string_view::npos) continue;
    e = field.find_first_not_of("+-", e + 1);
    if (e == std::string_view::npos || (e = field.find_first_not_of('0', e)) == std::string_view::npos)
      continue;
    const size_t digits = std::min(field.find_first_not_of("0123456789", e), field.size()) - e;
    if (digits >= 10)
      throw Error(fmt::format("{}: line {}: number {} is out of range", name, line, quoted(field)));
  }
}

// Checks one line before tinyobjloader reads it; true for a line it must not see. The first three
// fields of a `v` line must be numbers: tinyobjloader reads a coordinate it cannot parse ("nan", "inf",
// "1,5", a missing one) as 0, which would load a corrupt file as another mesh. Out-of-range numbers
// ("1e400") pass here and fail the coordinate check of vertex_for. Two extensions of tinyobjloader's
// own, which nimbus has no use for, are hidden from it: skin weights (`vw`: it converts their joint ids
// from a real to int unchecked, undefined behaviour for a huge or NaN one, found by fuzz/mesh_fuzz) and
// tags (`t`: each line allocates up to 8192 ints, reals and strings whatever it holds, ~350 KB from
// 20 bytes; a 38 KB file took 2 GB and 100 s with the double build).
bool check_line(std::string_view s, size_t line, const std::string& name) {
  const auto is_space = [](char ch) { return ch == ' ' || ch == '\t'; };  // tinyobjloader's IS_SPACE
  const size_t start = s.find_first_not_of(" \t");
  if (start == std::string_view::npos || s.size() < start + 2) return false;
  if (s[start] == 't' && is_space(s[start + 1])) return true;
  if (s[start] != 'v') return false;
  const char kind = is_space(s[start + 1]) ? ' ' : s[start + 1];  // v, vn, vt or vw
  if (kind != ' ' && (s.size() < start + 3 || !is_space(s[start + 2]))) return false;
  if (kind == 'w') return true;
  if (kind == 'n' || kind == 't' || kind == ' ') check_exponents(s.substr(start + 2), line, name);
  if (kind != ' ') return false;
  s.remove_prefix(start + 2);
  for (int c = 0; c < 3; ++c) {
    s.remove_prefix(std::min(s.find_first_not_of(" \t"), s.size()));
    const std::string_view field = s.substr(0, s.find_first_of(" \t"));
    s.remove_prefix(field.size());
    if (field.empty()) throw Error(fmt::format("{}: line {}: a vertex needs 3 coordinates", name, line));
    const char* first = field.data() + (field[0] == '+' ? 1 : 0);  // from_chars takes no '+'
    const char* last = field.data() + field.size();
    double x = 0.0;
    const auto [end, ec] = std::from_chars(first, last, x);
    if (ec == std::errc::invalid_argument || end != last)
      throw Error(
          fmt::format("{}: line {}: vertex coordinate {} is not a number", name, line, quoted(field)));
    if (ec == std::errc() && !std::isfinite(x))
      throw Error(fmt::format("{}: line {}: vertex coordinate {} is not finite", name, line, quoted(field)));
  }
  return false;
}

// Checks every line (ends at "\n", "\r\n" or a lone "\r", as tinyobjloader counts them). Returns the
// text to parse: `text` itself, or a copy in *masked with the hidden lines turned into comments (so
// tinyobjloader's line numbers stay right).
const std::string& checked_text(const std::string& text, const std::string& name, std::string* masked) {
  bool copied = false;
  size_t line = 0;
  for (size_t pos = 0; pos < text.size();) {
    size_t end = text.find_first_of("\r\n", pos);
    if (end == std::string::npos) end = text.size();
    if (check_line(std::string_view(text).substr(pos, end - pos), ++line, name)) {
      if (!copied) *masked = text;
      copied = true;
      (*masked)[text.find_first_not_of(" \t", pos)] = '#';
    }
    pos = end + (text.compare(end, 2, "\r\n") == 0 ? 2 : 1);
  }
  return copied ? *masked : text;
}

// One output vertex per distinct (position, normal) pair of the face corners, numbered in the order the
// corners first use them. Most positions go with one normal (or none): the first pair of each position
// is kept in a table indexed by the position, and only further pairs (hard edges) go into a hash map.
// (It replaced a std::map of every pair: docs/benchmarks.md, "Surfaces (issue 10)".)
class VertexTable {
 public:
  explicit VertexTable(size_t positions) : first_(positions, {-1, kNone}) {}
  // The output index of (v, n) (n = -1: no normal), or kNone after entering `next` for a new pair.
  uint32_t find_or_add(int v, int n, uint32_t next) {
    auto& [first_n, first_out] = first_[size_t(v)];
    if (first_out == kNone) {
      first_n = n;
      first_out = next;
      return kNone;
    }
    if (first_n == n) return first_out;
    const auto [it, inserted] = more_.try_emplace((uint64_t(uint32_t(v)) << 32) | uint32_t(n), next);
    return inserted ? kNone : it->second;
  }
  static constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();

 private:
  std::vector<std::pair<int, uint32_t>> first_;  // per position: its first normal and output vertex
  std::unordered_map<uint64_t, uint32_t> more_;  // (position << 32 | normal) of the further pairs
};

uint32_t vertex_for(const tinyobj::attrib_t& a, const tinyobj::index_t& idx, bool with_normals,
                    VertexTable& seen, TriangleMesh& m, const std::string& name) {
  const size_t nv = a.vertices.size() / 3, nn = a.normals.size() / 3;
  if (idx.vertex_index < 0)  // a relative index (-k) reaching back past the first vertex
    throw Error(fmt::format("{}: a face refers to a vertex before the first one", name));
  if (size_t(idx.vertex_index) >= nv)
    throw Error(fmt::format("{}: a face refers to vertex {} of {}", name, idx.vertex_index + 1, nv));
  const int n = with_normals ? idx.normal_index : -1;
  if (with_normals && size_t(n) >= nn)
    throw Error(fmt::format("{}: a face refers to normal {} of {}", name, n + 1, nn));
  const uint32_t out = uint32_t(m.vertex_count());
  if (const uint32_t known = seen.find_or_add(idx.vertex_index, n, out); known != VertexTable::kNone)
    return known;
  for (int c = 0; c < 3; ++c) {
    const double x = a.vertices[3 * size_t(idx.vertex_index) + c];
    if (!(std::abs(x) <= kMaxMeshCoordinate))
      throw Error(fmt::format("{}: vertex {} has a coordinate {} (must be finite, at most {:g} in size)",
                              name, idx.vertex_index + 1, x, kMaxMeshCoordinate));
    m.positions.push_back(float(x));
  }
  if (with_normals) {
    for (int c = 0; c < 3; ++c) {
      const double x = a.normals[3 * size_t(n) + c];
      m.normals.push_back(std::isfinite(x) ? float(x) : 0.0f);  // a bad normal falls back to the face's
    }
  }
  return out;
}

void check_triangle(const TriangleMesh& m, size_t t, const std::string& name) {
  const uint32_t* i = &m.indices[3 * t];
  const Vec3 a = m.position(i[0]), b = m.position(i[1]), c = m.position(i[2]);
  const Vec3 e1 = b - a, e2 = c - a;
  // Zero area relative to the edges' lengths: coincident or collinear corners.
  if (!(length(cross(e1, e2)) > 1e-12 * length(e1) * length(e2)) || length(e1) == 0.0 || length(e2) == 0.0)
    throw Error(fmt::format("{}: triangle {} is degenerate (zero area)", name, t + 1));
}

}  // namespace

TriangleMesh mesh_from_obj_text(const std::string& text, const std::string& name) {
  std::string masked;
  const std::string& input = checked_text(text, name, &masked);
  tinyobj::ObjReaderConfig config;
  config.triangulate = true;
  config.vertex_color = false;
  tinyobj::ObjReader reader;
  if (!reader.ParseFromString(input, "", config) || !reader.Error().empty()) {
    std::string why = reader.Error();
    while (!why.empty() && (why.back() == '\n' || why.back() == '\r')) why.pop_back();
    throw Error(fmt::format("{}: not a readable OBJ mesh: {}", name, why.empty() ? "parse error" : why));
  }
  const tinyobj::attrib_t& a = reader.GetAttrib();
  // Vertex normals are used only when every face corner names one.
  bool with_normals = !a.normals.empty();
  for (const tinyobj::shape_t& s : reader.GetShapes())
    for (const tinyobj::index_t& idx : s.mesh.indices) with_normals = with_normals && idx.normal_index >= 0;

  TriangleMesh m;
  VertexTable seen(a.vertices.size() / 3);
  for (const tinyobj::shape_t& s : reader.GetShapes()) {
    size_t corner = 0;
    for (const unsigned char fv : s.mesh.num_face_vertices) {
      if (fv == 3) {
        for (int k = 0; k < 3; ++k)
          m.indices.push_back(vertex_for(a, s.mesh.indices[corner + k], with_normals, seen, m, name));
        check_triangle(m, m.triangle_count() - 1, name);
      }
      corner += fv;  // faces tinyobjloader could not triangulate (fewer than 3 corners) are skipped
    }
  }
  if (m.triangle_count() == 0) throw Error(fmt::format("{}: the mesh has no triangles", name));
  if (m.vertex_count() > (size_t(1) << 31)) throw Error(fmt::format("{}: too many vertices", name));
  return m;
}

std::shared_ptr<const TriangleMesh> load_mesh(const std::filesystem::path& file, const std::string& name) {
  std::error_code ec;
  std::string ext = file.extension().string();
  for (char& ch : ext) ch = char(std::tolower(static_cast<unsigned char>(ch)));  // exporters write .OBJ too
  if (ext != ".obj")
    throw Error(
        fmt::format("{}: unsupported mesh format '{}' (supported: .obj)", name, file.extension().string()));
  if (!std::filesystem::exists(file, ec)) throw Error(fmt::format("{}: no such file", name));
  if (std::filesystem::is_directory(file, ec)) throw Error(fmt::format("{}: is a directory", name));
  // A FIFO or a device would block the read or never end (the volume loader refuses them the same way).
  if (!std::filesystem::is_regular_file(file, ec)) throw Error(fmt::format("{}: not a regular file", name));
  std::ifstream in(file, std::ios::binary | std::ios::ate);
  if (!in) throw Error(fmt::format("{}: cannot be opened for reading", name));
  // One sized read of the whole file (a stringstream's rdbuf copy was a third of a 1M-triangle load:
  // docs/benchmarks.md, "Surfaces (issue 10)").
  const std::streamoff size = in.tellg();
  if (size < 0) throw Error(fmt::format("{}: cannot be read", name));
  std::string text(size_t(size), '\0');
  in.seekg(0);
  if (!in.read(text.data(), size)) throw Error(fmt::format("{}: cannot be read", name));
  return std::make_shared<const TriangleMesh>(mesh_from_obj_text(text, name));
}

}  // namespace nimbus
