// The path length of a transient render's contributions (CameraSample::timed; docs/transient.md): a
// path traced from the camera keeps the length s walked from the camera to its current vertex, and each
// contribution adds the length of its light connection: the distance to the sampled point of a point,
// spot, sphere or rectangle light, to an emitting medium's point, or for a distant light (directional
// light, environment) the distance from the plane perpendicular to the light's direction that touches
// the media's bounding sphere on the light's side (the plane wave of a pulse entering the media at s = 0).
// Without bounded media that plane passes through the camera. Time is s / c with c = 1 (scene units).
#pragma once

#include <cmath>
#include <vector>

#include "integrators/integrator.h"
#include "scene/lights.h"

namespace nimbus {

// The bounding sphere of the media (centre, radius) that the distant lights' plane touches.
struct DistantReference {
  Vec3 centre{0.0, 0.0, 0.0};
  double radius = 0.0;
  DistantReference() = default;
  DistantReference(const SceneContext& ctx) : centre(ctx.camera.generate_ray(0.5, 0.5).o) {
    const Bounds& b = ctx.media.bounds();
    const Vec3 diagonal = b.hi - b.lo;
    if (b.empty() || !std::isfinite(diagonal.x + diagonal.y + diagonal.z)) return;
    centre = (b.lo + b.hi) * 0.5;
    radius = 0.5 * length(diagonal);
  }
  // The path length from the plane to p of light arriving at p from direction wi (unit, towards the light).
  double distance(const Vec3& p, const Vec3& wi) const { return radius + dot(centre - p, wi); }
};

// A path's clock: the sink for its timed contributions (null: a steady render, nothing recorded) and the
// length s walked from the camera to the current vertex.
struct PathClock {
  std::vector<TimedContribution>* out = nullptr;
  DistantReference distant;
  double s = 0.0;

  bool on() const { return out != nullptr; }
  size_t mark() const { return out ? out->size() : 0; }
  // c added to L, recorded at the path length s + extra.
  void add(Rgb& L, const Rgb& c, double extra, bool background = false) const {
    L += c;
    if (out) out->push_back({s + extra, c, background});
  }
  // The path walks from a to b: s grows by their distance.
  void walk(const Vec3& a, const Vec3& b) {
    if (out) s += length(b - a);
  }
  double from(const Vec3& a, const Vec3& b) const { return out ? length(b - a) : 0.0; }
  // The environment seen directly from the camera at o along d: c added to L, at the distant plane's
  // distance (a background part, which a transparent film leaves out).
  void background(Rgb& L, const Rgb& c, const Vec3& o, const Vec3& d) const {
    add(L, c, distant.distance(o, d), true);
  }
  // A light connection from the vertex p: c recorded (not added to any sum) with its length alone, for
  // settle() to complete.
  void record(double connection, const Rgb& c) const {
    if (out) out->push_back({connection, c, false});
  }
  // The length of a sampled light connection from p: the distance to the light's point, or for a
  // directional light the distant plane's.
  double connection(const Vec3& p, const LightSample& ls) const {
    return std::isfinite(ls.distance) ? ls.distance : distant.distance(p, ls.wi);
  }
  // Calls f, which records its contributions per unit throughput (record()), and settles them.
  template <class F>
  Rgb settled(const Rgb& beta, F&& f) const {
    const size_t from = mark();
    const Rgb r = f();
    settle(from, beta);
    return r;
  }
  // The contributions recorded since `from` were made at the current vertex, per unit throughput and
  // with their light connection's length: scaled by the throughput beta and moved to the camera.
  void settle(size_t from, const Rgb& beta) const {
    if (!out) return;
    for (size_t i = from; i < out->size(); ++i) (*out)[i].L *= beta, (*out)[i].s += s;
  }
};

}  // namespace nimbus
