// A triangle mesh as the scene holds it: float positions (Embree's vertex format), optional per-vertex
// normals, three indices per triangle. Loaded from a file by io/mesh.h, checked there (finite, bounded
// coordinates, indices in range, no degenerate triangles).
#pragma once

#include <cstdint>
#include <vector>

#include "core/math.h"

namespace nimbus {

class TriangleMesh {
 public:
  std::vector<float> positions;   // x y z per vertex
  std::vector<float> normals;     // x y z per vertex, or empty
  std::vector<uint32_t> indices;  // three per triangle

  size_t vertex_count() const { return positions.size() / 3; }
  size_t triangle_count() const { return indices.size() / 3; }
  Vec3 position(size_t v) const { return {positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]}; }
  Vec3 normal(size_t v) const { return {normals[3 * v], normals[3 * v + 1], normals[3 * v + 2]}; }
  size_t memory_bytes() const {
    return positions.size() * sizeof(float) + normals.size() * sizeof(float) +
           indices.size() * sizeof(uint32_t);
  }
};

}  // namespace nimbus
