// The scene's opaque surfaces behind one ray query, through Embree 3: meshes, rectangles and boxes as
// triangles, spheres as exact analytic user geometry. Queries are thread-safe; the Embree scene is
// built once, when the context is made.
#pragma once

#include <limits>
#include <memory>
#include <vector>

#include "core/math.h"
#include "nimbus/scene.h"

namespace nimbus {

struct SurfaceHit {
  double t = std::numeric_limits<double>::infinity();
  Vec3 p{0.0, 0.0, 0.0};
  Vec3 ng{0.0, 0.0, 1.0};  // geometric normal, unit, facing the ray's origin (-d side)
  Vec3 ns{0.0, 0.0, 1.0};  // shading normal (interpolated vertex normals), unit, on ng's side
  int surface = -1;        // index into Scene::surfaces
};

class SceneSurfaces {
 public:
  explicit SceneSurfaces(const std::vector<Surface>& surfaces);
  ~SceneSurfaces();
  SceneSurfaces(const SceneSurfaces&) = delete;
  SceneSurfaces& operator=(const SceneSurfaces&) = delete;

  bool empty() const { return surfaces_.empty(); }
  const Material& material(int i) const { return surfaces_[i].material; }
  // Bounds of all surfaces (empty when there are none).
  const Bounds& bounds() const { return bounds_; }

  // The first surface along o + t d (d unit) with t in (0, tmax); false (hit untouched) when none.
  bool intersect(const Vec3& o, const Vec3& d, double tmax, SurfaceHit* hit) const;
  // Whether any surface lies on o + t d for t in (0, tmax). Always false without surfaces.
  bool occluded(const Vec3& o, const Vec3& d, double tmax) const;

  // A ray origin for leaving the hit point in direction d: moved off the surface to d's side by
  // 1e-5 (|p| + t), which covers the float rounding of the hit (Embree intersects in float: the error
  // grows with the coordinates and with the distance travelled) in scenes of any unit.
  static Vec3 offset(const SurfaceHit& hit, const Vec3& d);

 private:
  struct Embree;
  std::vector<Surface> surfaces_;
  std::unique_ptr<Embree> embree_;
  Bounds bounds_;
};

}  // namespace nimbus
