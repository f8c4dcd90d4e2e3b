// Media whose extinction along a ray is known in closed form: every medium of the scene a sphere or a
// box of constant density (any transform), none emitting. Along o + t d the extinction is then piecewise
// constant, its pieces bounded by the chords of the shapes, so
// - the transmittance is exp(-sum_i sigma_t_i x chord_i) exactly (next-event estimation: zero variance,
//   where ratio tracking against a majorant equal to sigma_t is a 0/1 estimate of it), and
// - free flights are sampled against the exact extinction of each piece (grey media: no null
//   collisions; no majorant-grid cells to walk, one random number per piece instead of one per cell).
// The path tracer uses both where active() (integrators/tracking.h: track over the pieces).
#pragma once

#include <algorithm>
#include <array>
#include <vector>

#include "core/math.h"
#include "media/media.h"

namespace nimbus {

// The parametric interval [*t0, *t1] of the sphere (center, radius) along o + t d within [0, tmax] (d need
// not be unit); false when the ray misses it there.
bool sphere_chord(const Vec3& center, double radius, const Vec3& o, const Vec3& d, double tmax, double* t0,
                  double* t1);

class AnalyticMedia {
 public:
  AnalyticMedia() = default;  // inactive (tests: the majorant-grid path on analytic shapes)
  explicit AnalyticMedia(const SceneMedia& media);

  // Whether the scene has media and all of them are constant-density spheres and boxes without emission.
  bool active() const { return active_; }

  // The parametric interval [*t0, *t1] of medium i along o + t d within [0, tmax] (d need not be unit;
  // t in units of d). False when the ray misses it there.
  bool chord(int i, const Vec3& o, const Vec3& d, double tmax, double* t0, double* t1) const;

  // Transmittance exp(-optical depth) per channel along o + t d, t in (0, tmax) (d unit).
  Rgb transmittance(const Vec3& o, const Vec3& d, double tmax) const;

  // Visits the pieces of o + t d, t in (0, tmax), of constant non-zero extinction in order, calling
  // segment(t0, t1, majorant) -> bool (false stops); majorant = the largest channel of the piece's total
  // sigma_t, the tightest (twice it for a lone pure absorber: analytic_media.cpp); as MajorantGrid::traverse.
  template <typename F>
  void traverse(const Vec3& o, const Vec3& d, double tmax, F&& segment) const;

 private:
  struct Piece {
    Transform to_local;  // world -> the shape's space
    bool sphere = true;
    Vec3 center{0.0};
    double radius = 0.0;
    Bounds box;
    Rgb sigma_t{0.0};
    double majorant = 0.0;  // max channel of sigma_t
  };
  std::vector<Piece> media_;
  bool active_ = false;
};

template <typename F>
void AnalyticMedia::traverse(const Vec3& o, const Vec3& d, double tmax, F&& segment) const {
  const int n = int(media_.size());
  if (n == 1) {  // the common case: one shape, one piece
    double t0, t1;
    if (media_[0].majorant > 0.0 && chord(0, o, d, tmax, &t0, &t1) && t1 > t0)
      segment(t0, t1, media_[0].majorant);
    return;
  }
  // Several (possibly overlapping) shapes: cut the ray at every chord end, add the coefficients of the
  // media that cover each piece.
  std::array<double, 2 * kMaxMedia> ends;
  std::array<double, 2 * kMaxMedia> lo, hi;
  int m = 0;
  for (int i = 0; i < n; ++i) {
    lo[i] = hi[i] = 0.0;
    if (media_[i].majorant > 0.0 && chord(i, o, d, tmax, &lo[i], &hi[i]) && hi[i] > lo[i]) {
      ends[m++] = lo[i];
      ends[m++] = hi[i];
    }
  }
  std::sort(ends.begin(), ends.begin() + m);
  for (int k = 0; k + 1 < m; ++k) {
    const double t0 = ends[k], t1 = ends[k + 1];
    if (!(t1 > t0)) continue;
    const double mid = 0.5 * (t0 + t1);
    Rgb sigma_t(0.0);
    for (int i = 0; i < n; ++i)
      if (hi[i] > lo[i] && lo[i] <= mid && mid <= hi[i]) sigma_t += media_[i].sigma_t;
    const double maj = max_component(sigma_t);
    if (maj > 0.0 && !segment(t0, t1, maj)) return;
  }
}

}  // namespace nimbus
