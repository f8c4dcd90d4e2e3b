// The one tracking kernel (after pbrt-v4's SampleT_maj): tentative collisions distributed with the
// majorant density, cell by cell of the majorant grid (or piece by piece of analytic media, each with its
// exact extinction: media/analytic_media.h). Delta tracking (pathtrace), ratio tracking
// (transmittance) and the other integrators all build on it. Debug builds check its invariants
// (NIMBUS_DCHECK: majorants finite and non-negative, extinction in [0, majorant], weights finite and
// non-negative); Release builds compile the checks away.
#pragma once

#include <algorithm>
#include <cmath>
#include <utility>

#include "core/check.h"
#include "core/rng.h"
#include "media/analytic_media.h"
#include "media/majorant.h"
#include "media/media.h"
#include "scene/context.h"

namespace nimbus {

// Tentative collisions along the segments that visit(segment) hands to segment(t0, t1, majorant) -> bool in
// order (a majorant grid's cells, or an analytic medium's pieces): calls on_collision(p, majorant) -> bool
// at each; scale (in [0, 1]) multiplies every majorant. Returns true when the ray reached the end, false
// when the callback stopped it.
template <typename Visit, typename F>
bool track_segments(Visit&& visit, const Vec3& o, const Vec3& d, double scale, Rng& rng, F&& on_collision) {
  bool reached_end = true;
  visit([&](double t0, double t1, double segment_maj) {
    const double maj = segment_maj * scale;
    NIMBUS_DCHECK(maj >= 0.0 && std::isfinite(maj));
    if (maj <= 0.0) return true;
    double t = t0;
    while (true) {
      // Exponential step; memorylessness lets each segment restart at its entry. 1 - u is exact for the
      // generator's multiples of 2^-53, so log(1 - u) is log1p(-u) to rounding, at a third of its cost.
      t -= std::log(1.0 - rng.uniform()) / maj;
      if (t >= t1) return true;
      if (!on_collision(o + d * t, maj)) {
        reached_end = false;
        return false;
      }
    }
  });
  return reached_end;
}

// Calls on_collision(p, majorant) -> bool at tentative collisions along o + t d (d unit), t in
// (0, tmax), cell by cell of the majorant grid. Returns true when the ray reached tmax (or left the
// media), false when the callback stopped it.
// scale (in [0, 1]) multiplies every cell's majorant: for a density known to stay below that share
// of the extinction (mfs's photons see a reduced extinction), fewer tentative collisions.
template <typename F>
bool track(const MajorantGrid& grid, const Vec3& o, const Vec3& d, double tmax, double scale, Rng& rng,
           F&& on_collision) {
  return track_segments([&](auto&& segment) { grid.traverse(o, d, 0.0, tmax, segment); }, o, d, scale, rng,
                        std::forward<F>(on_collision));
}

template <typename F>
bool track(const MajorantGrid& grid, const Vec3& o, const Vec3& d, double tmax, Rng& rng, F&& on_collision) {
  return track(grid, o, d, tmax, 1.0, rng, std::forward<F>(on_collision));
}

// The same over the pieces of analytic media (media/analytic_media.h), each with its exact extinction
// as the majorant: with grey media every tentative collision is a real one.
template <typename F>
bool track(const AnalyticMedia& media, const Vec3& o, const Vec3& d, double tmax, Rng& rng,
           F&& on_collision) {
  return track_segments([&](auto&& segment) { media.traverse(o, d, tmax, segment); }, o, d, 1.0, rng,
                        std::forward<F>(on_collision));
}

// Free flights through the scene's media: over the analytic pieces where every medium is a constant-density
// shape (media/analytic_media.h), else cell by cell of the majorant grid.
template <typename F>
bool track(const SceneContext& ctx, const Vec3& o, const Vec3& d, double tmax, Rng& rng, F&& on_collision) {
  if (ctx.analytic.active()) return track(ctx.analytic, o, d, tmax, rng, on_collision);
  return track(ctx.majorants, o, d, tmax, rng, on_collision);
}

// The fixed-optical-depth march of the deterministic integrators: each majorant cell's segment of
// o + t d, t in (0, tmax), is cut into ceil(length * majorant / tau_step) equal steps, and
// on_step(p, t, dt) -> bool is called at fraction `offset` in [0, 1) of each step (0.5: midpoint; one
// uniform number per ray: a jittered, unbiased-in-the-limit march). Stops when on_step returns false.
template <typename F>
void march(const MajorantGrid& grid, const Vec3& o, const Vec3& d, double tmax, double tau_step,
           double offset, F&& on_step) {
  grid.traverse(o, d, 0.0, tmax, [&](double t0, double t1, double maj) {
    if (maj <= 0.0) return true;
    const int n = std::max(1, int(std::ceil((t1 - t0) * maj / tau_step)));
    const double dt = (t1 - t0) / n;
    for (int k = 0; k < n; ++k) {
      const double t = t0 + (k + offset) * dt;
      if (!on_step(o + d * t, t, dt)) return false;
    }
    return true;
  });
}

// The offsets of a growing march's steps: step k (along the whole ray) at fraction frac(u + k / phi) of
// itself, phi the golden ratio, from one uniform u per ray. Each step's offset is uniform, so each step's
// sample is unbiased for its step, as with one offset for all; but a shared offset puts every sample at
// the same place in its step, and where the integrand falls along the ray (the transmittance to the camera)
// every step errs the same way: an isotropic sphere of optical radius 2 (`a_sphere_iso_sun`) had 6 % noise
// per pixel from it. The golden-ratio sequence spreads the offsets evenly over [0, 1) within any few
// consecutive steps, so their errors cancel (docs/benchmarks.md, "The march's offsets").
class StepOffsets {
 public:
  explicit StepOffsets(double u) : u_(u) {}
  double next() {
    const double v = u_;
    u_ += 0.6180339887498949;  // 1 / phi
    if (u_ >= 1.0) u_ -= 1.0;
    return v;
  }

 private:
  double u_;
};

// The same with steps that may grow along the ray: each majorant cell's segment (t0, t1) is cut into
// steps of at most tau_step * scale(t0, t1) optical depth, scale (> 0) asked at the start of every cell
// (`mfs`: the blur and the attenuation grow with depth, so deeper light needs fewer samples; seed sec. 1;
// and cells that emit take steps of their own size). on_step(p, t, dt, u): the sample at t, fraction u of
// its step (StepOffsets from `offset`).
template <typename Scale, typename F>
void march_growing(const MajorantGrid& grid, const Vec3& o, const Vec3& d, double tmax, double tau_step,
                   double offset, Scale&& scale, F&& on_step) {
  StepOffsets offsets(offset);
  grid.traverse(o, d, 0.0, tmax, [&](double t0, double t1, double maj) {
    if (maj <= 0.0) return true;
    const int n = std::max(1, int(std::ceil((t1 - t0) * maj / (tau_step * scale(t0, t1)))));
    const double dt = (t1 - t0) / n;
    for (int k = 0; k < n; ++k) {
      const double u = offsets.next();
      const double t = t0 + (k + u) * dt;
      if (!on_step(o + d * t, t, dt, u)) return false;
    }
    return true;
  });
}

// The same over the pieces of analytic media (media/analytic_media.h), which have no cells: each step of at
// most tau_step * scale(t, t1) optical depth at the piece's extinction and at most max_step long, scale
// asked at the start of every step (t1: the piece's end), the last step of a piece ending at it. The steps follow the optical depth
// alone (a majorant grid's cells put at least one step in every cell crossed), and none falls outside
// the media.
template <typename Scale, typename F>
void march_growing(const AnalyticMedia& media, const Vec3& o, const Vec3& d, double tmax, double tau_step,
                   double max_step, double offset, Scale&& scale, F&& on_step) {
  StepOffsets offsets(offset);
  media.traverse(o, d, tmax, [&](double t0, double t1, double maj) {
    double t = t0;
    bool last = false;
    while (!last) {
      double dt = std::min(max_step, tau_step * scale(t, t1) / maj);
      last = !(t + dt < t1);
      if (last) dt = t1 - t;
      const double u = offsets.next();
      const double ts = t + u * dt;
      if (!on_step(o + d * ts, ts, dt, u)) return false;
      t += dt;
    }
    return true;
  });
}

// Unbiased per-channel transmittance along o + t d, t in (0, tmax), by ratio tracking against the
// extinction sigma(p) -> Rgb (at most the majorant), with Russian roulette once every channel has
// fallen below 0.1.
template <typename Sigma>
Rgb ratio_tracking(const MajorantGrid& grid, const Vec3& o, const Vec3& d, double tmax, Rng& rng,
                   Sigma&& sigma) {
  Rgb T(1.0);
  track(grid, o, d, tmax, rng, [&](const Vec3& p, double maj) {
    const Rgb sigma_t = sigma(p);
    // The null-collision share 1 - sigma_t / maj of each channel is in [0, 1].
    NIMBUS_DCHECK(min_component(sigma_t) >= 0.0 && max_component(sigma_t) <= maj);
    T *= Rgb(1.0) - sigma_t / maj;
    NIMBUS_DCHECK(min_component(T) >= 0.0 && std::isfinite(max_component(T)));
    const double m = max_component(T);
    if (m <= 0.0) {
      T = Rgb(0.0);
      return false;
    }
    if (m < 0.1) {
      if (rng.uniform() < 0.5) {
        T = Rgb(0.0);
        return false;
      }
      T *= 2.0;
    }
    return true;
  });
  return T;
}

// The same with the media's full extinction.
inline Rgb ratio_tracking_transmittance(const SceneMedia& media, const MajorantGrid& grid, const Vec3& o,
                                        const Vec3& d, double tmax, Rng& rng) {
  return ratio_tracking(grid, o, d, tmax, rng, [&](const Vec3& p) { return media.sigma_t(p); });
}

}  // namespace nimbus
