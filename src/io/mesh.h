// Triangle meshes from Wavefront OBJ files, through tinyobjloader: polygons triangulated, per-vertex
// normals kept when every face corner has one. Checked: finite coordinates within kMaxMeshCoordinate,
// indices in range, at least one triangle, no degenerate (zero-area) triangle; every `v` line's
// coordinates numbers. tinyobjloader's own `vw` and `t` extensions are ignored (mesh.cpp says why).
#pragma once

#include <filesystem>
#include <memory>
#include <string>

#include "scene/mesh.h"

namespace nimbus {

inline constexpr double kMaxMeshCoordinate = 1e15;

// Parses OBJ text; errors are nimbus::Errors that start with `name` (the file as the user wrote it).
TriangleMesh mesh_from_obj_text(const std::string& text, const std::string& name);
// Reads and parses an .obj file (the only format supported).
std::shared_ptr<const TriangleMesh> load_mesh(const std::filesystem::path& file, const std::string& name);

}  // namespace nimbus
