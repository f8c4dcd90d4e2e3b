#include "media/media.h"

#include <fmt/format.h>

#include "media/density_grid.h"
#include "nimbus/error.h"

namespace nimbus {

namespace {

// Grid-world point of a vdb shape: undo translate, then scale.
Vec3 vdb_grid_world(const VdbShape& v, const Vec3& p) { return (p - v.translate) / v.scale; }

const DensityGrid* grid_of(const Shape& s) {
  if (const auto* v = std::get_if<VdbShape>(&s)) return v->data.get();
  if (const auto* c = std::get_if<CloudShape>(&s)) return c->data.get();
  return nullptr;
}

// World bounds of the index-space box [lo, hi] of a grid seen through an affine map f.
template <typename F>
Bounds transform_box(const Vec3& lo, const Vec3& hi, F&& f) {
  Bounds b;
  for (int k = 0; k < 8; ++k)
    b.extend(f(Vec3(k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z)));
  return b;
}

}  // namespace

SceneMedia::SceneMedia(const std::vector<Medium>& media) : media_(media) {
  if (media_.size() > size_t(kMaxMedia))
    throw Error(fmt::format("too many media: {} (at most {})", media_.size(), kMaxMedia));
  for (const Medium& m : media_) {
    Bounds b;
    if (const auto* s = std::get_if<SphereShape>(&m.shape)) {
      b.extend(s->center - Vec3(s->radius));
      b.extend(s->center + Vec3(s->radius));
    } else if (const auto* x = std::get_if<BoxShape>(&m.shape)) {
      b.extend(x->min);
      b.extend(x->max);
    } else if (const auto* v = std::get_if<VdbShape>(&m.shape)) {
      const DensityGrid& g = *v->data;
      b = transform_box(g.index_lo(), g.index_hi(),
                        [&](const Vec3& i) { return g.index_to_world(i) * v->scale + v->translate; });
    } else if (const auto* c = std::get_if<CloudShape>(&m.shape)) {
      const DensityGrid& g = *c->data;
      b = transform_box(g.index_lo(), g.index_hi(), [&](const Vec3& i) { return g.index_to_world(i); });
    }
    medium_bounds_.push_back(b);
    bounds_.extend(b);
  }
}

double SceneMedia::density(int i, const Vec3& p) const {
  const Shape& s = media_[i].shape;
  if (!medium_bounds_[i].contains(p)) return 0.0;
  if (const auto* sp = std::get_if<SphereShape>(&s))
    return (p - sp->center).length2() <= sp->radius * sp->radius;
  if (std::holds_alternative<BoxShape>(s)) return 1.0;
  if (const auto* v = std::get_if<VdbShape>(&s))
    return v->data->density_index(v->data->world_to_index(vdb_grid_world(*v, p)));
  const DensityGrid* g = grid_of(s);
  return g->density_index(g->world_to_index(p));
}

double SceneMedia::max_density(int i, const Bounds& box) const {
  if (!medium_bounds_[i].overlaps(box)) return 0.0;
  const Shape& s = media_[i].shape;
  if (const auto* sp = std::get_if<SphereShape>(&s)) {
    double d2 = 0.0;  // squared distance from the centre to the box
    for (int a = 0; a < 3; ++a) {
      const double c = std::clamp(sp->center[a], box.lo[a], box.hi[a]) - sp->center[a];
      d2 += c * c;
    }
    return d2 <= sp->radius * sp->radius ? 1.0 : 0.0;
  }
  if (std::holds_alternative<BoxShape>(s)) return 1.0;
  const DensityGrid* g = grid_of(s);
  const auto* v = std::get_if<VdbShape>(&s);
  const Bounds ib = transform_box(
      box.lo, box.hi, [&](const Vec3& p) { return g->world_to_index(v ? vdb_grid_world(*v, p) : p); });
  return g->max_density_index(ib.lo, ib.hi);
}

void SceneMedia::eval(const Vec3& p, MediumPoint* out) const {
  out->count = count();
  out->sigma_s = Rgb(0.0);
  out->sigma_a = Rgb(0.0);
  for (int i = 0; i < count(); ++i) {
    const double d = density(i, p);
    out->sigma_s_i[i] = media_[i].sigma_s * d;
    out->sigma_s += out->sigma_s_i[i];
    out->sigma_a += media_[i].sigma_a * d;
  }
}

Rgb SceneMedia::sigma_t(const Vec3& p) const {
  Rgb s(0.0);
  for (int i = 0; i < count(); ++i) {
    const double d = density(i, p);
    if (d != 0.0) s += (media_[i].sigma_s + media_[i].sigma_a) * d;
  }
  return s;
}

}  // namespace nimbus
