// OBJ meshes (io/mesh.h).
#include "io/mesh.h"

#include <fmt/format.h>
#include <tiny_obj_loader.h>

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <utility>

#include "nimbus/error.h"

namespace nimbus {

namespace {

// One output vertex per distinct (position, normal) pair of the face corners.
uint32_t vertex_for(const tinyobj::attrib_t& a, const tinyobj::index_t& idx, bool with_normals,
                    std::map<std::pair<int, int>, uint32_t>& seen, TriangleMesh& m, const std::string& name) {
  const size_t nv = a.vertices.size() / 3, nn = a.normals.size() / 3;
  if (idx.vertex_index < 0 || size_t(idx.vertex_index) >= nv)
    throw Error(fmt::format("{}: a face refers to vertex {} of {}", name, idx.vertex_index + 1, nv));
  const int n = with_normals ? idx.normal_index : -1;
  if (with_normals && size_t(n) >= nn)
    throw Error(fmt::format("{}: a face refers to normal {} of {}", name, n + 1, nn));
  const auto [it, inserted] = seen.try_emplace({idx.vertex_index, n}, uint32_t(m.vertex_count()));
  if (!inserted) return it->second;
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
  return it->second;
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
  tinyobj::ObjReaderConfig config;
  config.triangulate = true;
  config.vertex_color = false;
  tinyobj::ObjReader reader;
  if (!reader.ParseFromString(text, "", config) || !reader.Error().empty()) {
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
  std::map<std::pair<int, int>, uint32_t> seen;
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
  if (file.extension() != ".obj")
    throw Error(
        fmt::format("{}: unsupported mesh format '{}' (supported: .obj)", name, file.extension().string()));
  if (!std::filesystem::exists(file, ec)) throw Error(fmt::format("{}: no such file", name));
  if (std::filesystem::is_directory(file, ec)) throw Error(fmt::format("{}: is a directory", name));
  std::ifstream in(file, std::ios::binary);
  if (!in) throw Error(fmt::format("{}: cannot be opened for reading", name));
  std::ostringstream text;
  text << in.rdbuf();
  return std::make_shared<const TriangleMesh>(mesh_from_obj_text(text.str(), name));
}

}  // namespace nimbus
