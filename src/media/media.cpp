#include "media/media.h"

#include <fmt/format.h>

#include "media/density_grid.h"
#include "nimbus/error.h"

namespace nimbus {

namespace {

// Grid-world point of a vdb shape: undo translate, then scale (x / 1 is x: no divisions at scale 1).
Vec3 vdb_grid_world(const VdbShape& v, const Vec3& p) {
  return v.scale == 1.0 ? p - v.translate : (p - v.translate) / v.scale;
}

const DensityGrid* grid_of(const Shape& s) {
  if (const auto* v = std::get_if<VdbShape>(&s)) return v->data.get();
  if (const auto* c = std::get_if<CloudShape>(&s)) return c->data.get();
  return nullptr;
}

// Index-space point of a grid shape at a local (shape-space) point.
Vec3 grid_index(const Shape& s, const DensityGrid& g, const Vec3& local) {
  const auto* v = std::get_if<VdbShape>(&s);
  return g.world_to_index(v ? vdb_grid_world(*v, local) : local);
}

// World bounds of medium m: its shape's local bounds through its transform. Analytic shapes are mapped
// exactly (a sphere's image is an ellipsoid: half-extent r |row a of M| along world axis a), grid shapes
// by the 8 corners of their index box through the whole chain index -> grid world -> local -> world.
Bounds world_bounds(const Medium& m) {
  const Transform& t = m.transform;
  if (const auto* s = std::get_if<SphereShape>(&m.shape)) {
    if (t.is_identity()) return Bounds{s->center - Vec3(s->radius), s->center + Vec3(s->radius)};
    const Vec3 c = t.point(s->center);
    const auto& a = t.matrix();
    Vec3 half;
    for (int r = 0; r < 3; ++r)
      half[r] = s->radius * std::sqrt(a[r][0] * a[r][0] + a[r][1] * a[r][1] + a[r][2] * a[r][2]);
    return Bounds{c - half, c + half};
  }
  if (const auto* x = std::get_if<BoxShape>(&m.shape)) return transform_bounds(t, Bounds{x->min, x->max});
  const DensityGrid& g = *grid_of(m.shape);
  const auto* v = std::get_if<VdbShape>(&m.shape);
  auto to_world = [&](const Vec3& grid_world) {
    const Vec3 local = v ? grid_world * v->scale + v->translate : grid_world;
    return t.is_identity() ? local : t.point(local);
  };
  Bounds b = bounds_of_mapped_box(g.index_lo(), g.index_hi(),
                                  [&](const Vec3& i) { return to_world(g.index_to_world(i)); });
  // The emission, temperature and colour grids may reach beyond the density grid.
  if (const Bounds e = MediumEmissionField(m).grid_bounds(); !e.empty())
    b.extend(bounds_of_mapped_box(e.lo, e.hi, to_world));
  return b;
}

}  // namespace

SceneMedia::SceneMedia(const std::vector<Medium>& media) : media_(media) {
  if (media_.size() > size_t(kMaxMedia))
    throw Error(fmt::format("too many media: {} (at most {})", media_.size(), kMaxMedia));
  for (const Medium& m : media_) {
    medium_bounds_.push_back(world_bounds(m));
    bounds_.extend(medium_bounds_.back());
    to_local_.push_back(m.transform.inverse());
    fields_.emplace_back(m);
    emits_ = emits_ || fields_.back().emits();
    tints_ = tints_ || fields_.back().tints();
  }
}

Vec3 SceneMedia::grid_world(int i, const Vec3& p) const {
  const Vec3 q = to_local_[i].is_identity() ? p : to_local_[i].point(p);
  const auto* v = std::get_if<VdbShape>(&media_[i].shape);
  return v ? vdb_grid_world(*v, q) : q;
}

bool SceneMedia::may_emit(int i, const Bounds& box) const {
  if (!fields_[i].emits() || !medium_bounds_[i].overlaps(box)) return false;
  const Bounds gw = bounds_of_mapped_box(box.lo, box.hi, [&](const Vec3& p) { return grid_world(i, p); });
  return fields_[i].may_emit(gw, max_density(i, box));
}

Rgb SceneMedia::emission(const Vec3& p) const {
  Rgb j(0.0);
  for (int i = 0; i < count(); ++i)
    if (fields_[i].emits() && medium_bounds_[i].contains(p))
      j += fields_[i].emission(grid_world(i, p), density(i, p));
  return j;
}

double SceneMedia::density(int i, const Vec3& p) const {
  if (!medium_bounds_[i].contains(p)) return 0.0;
  const Shape& s = media_[i].shape;
  const bool identity = to_local_[i].is_identity();
  const Vec3 q = identity ? p : to_local_[i].point(p);  // local (shape-space) point
  if (const auto* sp = std::get_if<SphereShape>(&s))
    return (q - sp->center).length2() <= sp->radius * sp->radius;
  if (const auto* b = std::get_if<BoxShape>(&s)) return identity || Bounds{b->min, b->max}.contains(q);
  const DensityGrid* g = grid_of(s);
  return g->density_index(grid_index(s, *g, q));
}

bool SceneMedia::inside(const Vec3& p) const {
  for (int i = 0; i < count(); ++i)
    if (density(i, p) > 0.0) return true;
  return false;
}

double SceneMedia::max_density(int i, const Bounds& box, bool exact) const {
  if (!medium_bounds_[i].overlaps(box)) return 0.0;
  const Shape& s = media_[i].shape;
  const Transform& to_local = to_local_[i];
  // The world box in local space: the bounds of its 8 corners (they hold the box's whole image), widened
  // by far more than the rounding of the mapping so that a point on the box's edge stays inside.
  Bounds local = transform_bounds(to_local, box);
  if (!to_local.is_identity()) {
    for (int a = 0; a < 3; ++a) {
      const double pad = 1e-9 * (std::abs(local.lo[a]) + std::abs(local.hi[a]));
      local.lo[a] -= pad;
      local.hi[a] += pad;
    }
  }
  if (const auto* sp = std::get_if<SphereShape>(&s)) {
    double d2 = 0.0;  // squared distance from the centre to the box
    for (int a = 0; a < 3; ++a) {
      const double c = std::clamp(sp->center[a], local.lo[a], local.hi[a]) - sp->center[a];
      d2 += c * c;
    }
    return d2 <= sp->radius * sp->radius ? 1.0 : 0.0;
  }
  if (const auto* b = std::get_if<BoxShape>(&s))
    return to_local.is_identity() || Bounds{b->min, b->max}.overlaps(local) ? 1.0 : 0.0;
  // Grids: the world box's corners through the whole chain world -> local -> index (one affine map).
  const DensityGrid* g = grid_of(s);
  const Bounds ib = bounds_of_mapped_box(box.lo, box.hi, [&](const Vec3& p) {
    return grid_index(s, *g, to_local.is_identity() ? p : to_local.point(p));
  });
  return exact ? g->max_density_index_exact(ib.lo, ib.hi) : g->max_density_index(ib.lo, ib.hi);
}

void SceneMedia::eval(const Vec3& p, MediumPoint* out) const {
  out->count = count();
  out->sigma_s = Rgb(0.0);
  out->sigma_a = Rgb(0.0);
  out->emission = Rgb(0.0);
  for (int i = 0; i < count(); ++i) {
    const double d = density(i, p);
    out->sigma_s_i[i] = media_[i].sigma_s * d;
    if ((emits_ || tints_) && (fields_[i].emits() || fields_[i].tints()) && medium_bounds_[i].contains(p)) {
      const Vec3 gw = grid_world(i, p);
      if (d > 0.0 && fields_[i].tints()) out->sigma_s_i[i] *= fields_[i].tint(gw);
      out->emission += fields_[i].emission(gw, d);
    }
    out->sigma_s += out->sigma_s_i[i];
    out->sigma_a += media_[i].sigma_a * d;
  }
}

Rgb SceneMedia::sigma_t(const Vec3& p) const {
  Rgb s(0.0);
  for (int i = 0; i < count(); ++i) {
    const double d = density(i, p);
    if (d == 0.0) continue;
    s += (tints_ && fields_[i].tints() ? media_[i].sigma_s * fields_[i].tint(grid_world(i, p))
                                       : media_[i].sigma_s) *
             d +
         media_[i].sigma_a * d;
  }
  return s;
}

}  // namespace nimbus
