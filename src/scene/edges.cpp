#include "scene/edges.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <limits>
#include <variant>

#include "media/analytic_media.h"

namespace nimbus {

namespace {

// What a ray sees of the outlines: the first surface it meets (-1: none) and the sphere and box media it
// crosses before that surface (bit i for medium i; media past the 64th are left out).
struct Sight {
  int surface = -1;
  uint64_t media = 0;
  bool operator==(const Sight&) const = default;
};

bool crosses_shape(const Medium& m, const Transform& to_local, const Vec3& o, const Vec3& d, double tmax) {
  const bool identity = to_local.is_identity();
  const Vec3 lo = identity ? o : to_local.point(o), ld = identity ? d : to_local.vector(d);
  double t0, t1;
  if (const auto* s = std::get_if<SphereShape>(&m.shape))
    return sphere_chord(s->center, s->radius, lo, ld, tmax, &t0, &t1) && t1 > t0;
  if (const auto* b = std::get_if<BoxShape>(&m.shape))
    return Bounds{b->min, b->max}.intersect(lo, ld, 0.0, tmax, &t0, &t1) && t1 > t0;
  return false;  // a density grid or procedural cloud: no hard outline
}

Sight sight(const SceneContext& ctx, const std::vector<Transform>& to_local, double px, double py) {
  const Ray r = ctx.camera.generate_ray(px, py);
  Sight s;
  SurfaceHit hit;
  double tmax = std::numeric_limits<double>::infinity();
  if (!ctx.surfaces.empty() && ctx.surfaces.intersect(r.o, r.d, tmax, &hit)) {
    s.surface = hit.surface;
    tmax = hit.t;
  }
  for (int i = 0; i < int(to_local.size()); ++i)
    if (crosses_shape(ctx.media.medium(i), to_local[i], r.o, r.d, tmax)) s.media |= uint64_t(1) << i;
  return s;
}

}  // namespace

std::vector<PixelEdge> edge_pixels(const SceneContext& ctx, const Region& window) {
  const int W = ctx.camera.width(), H = ctx.camera.height();
  // The window grown by one pixel (within the image): its outline pixels mark the window's `beside` ones.
  const int x0 = std::max(window.x0 - 1, 0), y0 = std::max(window.y0 - 1, 0);
  const int x1 = std::min(window.x1 + 1, W), y1 = std::min(window.y1 + 1, H);
  const int gw = x1 - x0, gh = y1 - y0;
  const int ww = window.x1 - window.x0, wh = window.y1 - window.y0;
  std::vector<PixelEdge> out(size_t(ww) * size_t(wh), PixelEdge::none);
  std::vector<Transform> to_local;
  bool shapes = false;
  for (int i = 0; i < std::min(ctx.media.count(), 64); ++i) {
    const Medium& m = ctx.media.medium(i);
    shapes |= std::holds_alternative<SphereShape>(m.shape) || std::holds_alternative<BoxShape>(m.shape);
    to_local.push_back(m.transform.inverse());
  }
  if (!shapes && ctx.surfaces.empty()) return out;  // density grids alone: no hard outline
  // Row by row (each row's two lines of corner rays of its own: the corners of the image are never held
  // at once).
  std::vector<uint8_t> outline(size_t(gw) * size_t(gh));
  tbb::parallel_for(0, gh, [&](int j) {
    std::vector<Sight> top(size_t(gw) + 1), bottom(size_t(gw) + 1);
    for (int i = 0; i <= gw; ++i) {
      top[i] = sight(ctx, to_local, x0 + i, y0 + j);
      bottom[i] = sight(ctx, to_local, x0 + i, y0 + j + 1);
    }
    for (int i = 0; i < gw; ++i)
      outline[size_t(j) * gw + i] = !(top[i + 1] == top[i] && bottom[i] == top[i] && bottom[i + 1] == top[i]);
  });
  for (int y = window.y0; y < window.y1; ++y)
    for (int x = window.x0; x < window.x1; ++x) {
      PixelEdge& e = out[size_t(y - window.y0) * ww + (x - window.x0)];
      if (outline[size_t(y - y0) * gw + (x - x0)]) {
        e = PixelEdge::outline;
        continue;
      }
      for (int v = std::max(y - 1, y0); v <= std::min(y + 1, y1 - 1) && e == PixelEdge::none; ++v)
        for (int u = std::max(x - 1, x0); u <= std::min(x + 1, x1 - 1); ++u)
          if (outline[size_t(v - y0) * gw + (u - x0)]) e = PixelEdge::beside;
    }
  return out;
}

}  // namespace nimbus
