// libFuzzer target: OBJ text -> nimbus::mesh_from_obj_text (src/io/mesh.cpp: the vertex-line check,
// tinyobjloader's parser and triangulation, the index, coordinate and degeneracy checks). A
// nimbus::Error is a clean rejection; anything else escaping, a sanitizer report, a leak, a timeout,
// or a mesh returned that breaks TriangleMesh's contract (no triangles, an index out of range, a
// coordinate beyond kMaxMeshCoordinate, normals for some vertices only) is a bug.
//
// tinyobjloader's implementation is compiled into this target, so its parser is instrumented like
// nimbus's own code: these definitions take precedence over Debian's libtinyobjloader.so (built from
// the same header, 32-bit float reals as here: the target tinyobjloader::tinyobjloader sets no
// TINYOBJLOADER_USE_DOUBLE), which the library links.
// Without them libFuzzer would see no coverage inside the parser and ASan no access it makes.
#define TINYOBJLOADER_IMPLEMENTATION
#include <tiny_obj_loader.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "io/mesh.h"
#include "nimbus/error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  nimbus::TriangleMesh m;
  try {
    m = nimbus::mesh_from_obj_text(text, "fuzz.obj");
  } catch (const nimbus::Error&) {
    return 0;
  }
  if (m.triangle_count() == 0 || m.indices.size() % 3 != 0 || m.positions.size() % 3 != 0) __builtin_trap();
  if (!m.normals.empty() && m.normals.size() != m.positions.size()) __builtin_trap();
  for (const uint32_t i : m.indices)
    if (i >= m.vertex_count()) __builtin_trap();
  for (const float x : m.positions)
    if (!(std::abs(double(x)) <= 1.0000001 * nimbus::kMaxMeshCoordinate)) __builtin_trap();
  for (const float x : m.normals)
    if (!std::isfinite(x)) __builtin_trap();
  return 0;
}
