#include "media/analytic_media.h"

#include <cmath>

namespace nimbus {

bool sphere_chord(const Vec3& center, double radius, const Vec3& o, const Vec3& d, double tmax, double* t0,
                  double* t1) {
  // |o + t d - c|^2 = r^2: a t^2 + 2 b t + c = 0, the roots in the cancellation-free form.
  const Vec3 oc = o - center;
  const double a = dot(d, d), b = dot(d, oc), c = dot(oc, oc) - radius * radius;
  const double disc = b * b - a * c;
  if (!(disc > 0.0) || !(a > 0.0)) return false;
  const double q = -(b + std::copysign(std::sqrt(disc), b));
  double r0 = q / a, r1 = q != 0.0 ? c / q : -r0;
  if (r0 > r1) std::swap(r0, r1);
  *t0 = std::max(r0, 0.0);
  *t1 = std::min(r1, tmax);
  return *t0 <= *t1;
}

AnalyticMedia::AnalyticMedia(const SceneMedia& media) {
  active_ = media.count() > 0 && !media.emits();
  for (int i = 0; i < media.count() && active_; ++i) {
    const Medium& m = media.medium(i);
    Piece p;
    p.to_local = m.transform.inverse();
    p.sigma_t = m.sigma_s + m.sigma_a;
    p.majorant = max_component(p.sigma_t);
    // A pure absorber alone on the ray (no scattering anywhere in it) gets twice its extinction as the
    // majorant: against the exact one every tentative collision would end the path (an analogue
    // absorption, and the camera ray's layers behind it, depth and holdout, lost with it); with half of
    // them null collisions the path goes on with the ratio-tracking weight (1 - sigma_t / majorant per
    // collision). (Several media: each piece's majorant is its exact extinction.)
    if (max_component(m.sigma_s) <= 0.0) p.majorant *= 2.0;
    if (const auto* s = std::get_if<SphereShape>(&m.shape)) {
      p.center = s->center;
      p.radius = s->radius;
    } else if (const auto* b = std::get_if<BoxShape>(&m.shape)) {
      p.sphere = false;
      p.box = Bounds{b->min, b->max};
    } else {
      active_ = false;  // a density grid: tracked against the majorant grid
    }
    media_.push_back(p);
  }
  if (!active_) media_.clear();
}

bool AnalyticMedia::chord(int i, const Vec3& o, const Vec3& d, double tmax, double* t0, double* t1) const {
  const Piece& m = media_[i];
  // The ray in the shape's space: the same parameter t (the map is affine).
  const bool identity = m.to_local.is_identity();
  const Vec3 lo = identity ? o : m.to_local.point(o), ld = identity ? d : m.to_local.vector(d);
  if (!m.sphere) return m.box.intersect(lo, ld, 0.0, tmax, t0, t1);
  return sphere_chord(m.center, m.radius, lo, ld, tmax, t0, t1);
}

Rgb AnalyticMedia::transmittance(const Vec3& o, const Vec3& d, double tmax) const {
  // Overlapping media add their coefficients, so the optical depth is the sum over media of
  // sigma_t x chord length.
  Rgb tau(0.0);
  for (int i = 0; i < int(media_.size()); ++i) {
    double t0, t1;
    if (chord(i, o, d, tmax, &t0, &t1)) tau += media_[i].sigma_t * (t1 - t0);
  }
  return exp_channels(-tau);
}

}  // namespace nimbus
