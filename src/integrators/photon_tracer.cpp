// The photon tracer's emission and batching (integrators/photon_tracer.h).
#include "integrators/photon_tracer.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "integrators/env_light.h"
#include "scene/area_lights.h"
#include "scene/lights.h"

namespace nimbus {

namespace {

// A point or spot light at x and the media's sphere (c, r): the distance to c, the cone towards the sphere
// (cos_aim; -1 from inside it) and a spot's own cone (cos_spot; -1 for a point light).
struct LightCones {
  double dist, cos_aim, cos_spot;
};
LightCones light_cones(const Vec3& x, const SpotLight* spot, const Vec3& c, double r) {
  const double dist = (c - x).length();
  return {dist, dist > r ? std::sqrt(std::max(0.0, 1.0 - r * r / (dist * dist))) : -1.0,
          spot ? std::cos(0.5 * spot->cone_angle_deg * kPi / 180.0) : -1.0};
}

}  // namespace

Photon emit(const SceneContext& ctx, size_t source, const Vec3& c, double r, double n, Rng& rng,
            const double* strat) {
  double u1 = rng.uniform(), u2 = rng.uniform(), u3 = rng.uniform(), u4 = rng.uniform();
  if (strat) u1 = u3 = strat[0], u2 = u4 = strat[1];
  const double disc_area = kPi * r * r;
  auto through_disc = [&](const Vec3& w) {
    const Frame frame(w);
    const double rr = r * std::sqrt(u3), phi = 2.0 * kPi * u4;
    return c - w * (2.0 * r) + frame.to_world({rr * std::cos(phi), rr * std::sin(phi), 0.0});
  };
  Photon p;
  if (source < ctx.lights.size()) {
    const Light& light = ctx.lights[source];
    if (const auto* d = std::get_if<DirectionalLight>(&light)) {
      p.w = normalize(d->direction);
      p.x = through_disc(p.w);
      p.power = d->irradiance * (disc_area / n);
    } else if (std::holds_alternative<PointLight>(light) || std::holds_alternative<SpotLight>(light)) {
      // A point light (a spot: times its falloff in the photon's direction) towards the media's sphere.
      const auto* pt = std::get_if<PointLight>(&light);
      const auto* spot = std::get_if<SpotLight>(&light);
      p.x = pt ? pt->position : spot->position;
      const Vec3 v = c - p.x;
      // The narrower of the cone towards the media's sphere and a spot's own cone (both hold every
      // direction that carries power into the media).
      const auto [dist, cos_aim, cos_spot] = light_cones(p.x, spot, c, r);
      if (cos_spot > cos_aim) {
        p.w = spherical_direction(1.0 - u1 * (1.0 - cos_spot), 2.0 * kPi * u2, spot->direction);
        p.power = Rgb(2.0 * kPi * (1.0 - cos_spot) / n);
      } else if (dist > r) {
        const double cos_max = cos_aim;
        p.w = spherical_direction(1.0 - u1 * (1.0 - cos_max), 2.0 * kPi * u2, v / dist);
        p.power = Rgb(2.0 * kPi * (1.0 - cos_max) / n);
      } else {
        p.w = spherical_direction(1.0 - 2.0 * u1, 2.0 * kPi * u2, Vec3(0, 0, 1));
        p.power = Rgb(4.0 * kPi / n);
      }
      p.power *= pt ? pt->intensity : spot->intensity * spot_falloff(*spot, dot(p.w, spot->direction));
    } else {
      // An area light: a uniform point of it, a cosine-weighted direction. (Only the beam grid, which
      // leaves area lights out, passes a stratified sample.)
      emit_area_photon(light, n, u1, u2, u3, u4, &p.x, &p.w, &p.power);
    }
  } else if (!ctx.env_map) {
    // Uniform radiance L from every direction: flux L 4 pi A through a disc of area A.
    p.w = spherical_direction(1.0 - 2.0 * u1, 2.0 * kPi * u2, Vec3(0, 0, 1));
    p.x = through_disc(p.w);
    p.power = ctx.environment * (4.0 * kPi * disc_area / n);
  } else {
    // An environment image (with any constant part): arriving along wi with density pdf(wi), flux
    // L(wi) A / pdf(wi) through the disc (integrators/env_light.h: env_photon_direction).
    double pdf = 0.0;
    const Vec3 wi = env_photon_direction(ctx, u1, u2, &pdf);
    p.w = -wi;
    p.x = through_disc(p.w);
    p.power = pdf > 0.0 ? ctx.environment_radiance(wi) * (disc_area / (pdf * n)) : Rgb(0.0);
  }
  return p;
}

namespace {

// The raster cell index of a plane coordinate x in [-half, half] (clamped).
int raster_index(const LightFootprint& fp, double x) {
  return std::clamp(int(std::floor((x + fp.half) / fp.cell)), 0, fp.res - 1);
}

// Marks the raster cells of the rectangle [u0, u1] x [v0, v1] (widened by 1e-6 of a cell against rounding).
void mark(const LightFootprint& fp, double u0, double u1, double v0, double v1,
          std::vector<uint8_t>* marked) {
  const double eps = 1e-6 * fp.cell;
  for (int v = raster_index(fp, v0 - eps); v <= raster_index(fp, v1 + eps); ++v)
    for (int u = raster_index(fp, u0 - eps); u <= raster_index(fp, u1 + eps); ++u)
      (*marked)[size_t(v) * fp.res + u] = 1;
}

// The footprint's raster over [-half, half]^2 (cells of half the majorant grid's smallest cell side), the cells
// that rect(lo, size) marks for each non-empty majorant cell (corner lo, sides size), and the cells kept.
template <typename Rect>
void rasterise(const MajorantGrid& majorants, LightFootprint* fp, Rect&& rect) {
  const Bounds b = majorants.bounds();
  const auto m = majorants.resolution();
  const Vec3 size = (b.hi - b.lo) / Vec3(m[0], m[1], m[2]);
  fp->res = std::clamp(int(std::ceil(4.0 * fp->half / std::min({size.x, size.y, size.z}))), 8, 512);
  fp->cell = 2.0 * fp->half / fp->res;
  std::vector<uint8_t> marked(size_t(fp->res) * fp->res, 0);
  for (int z = 0; z < m[2]; ++z)
    for (int y = 0; y < m[1]; ++y)
      for (int x = 0; x < m[0]; ++x)
        if (majorants.cell_majorant(x, y, z) > 0.0) rect(b.lo + Vec3(x, y, z) * size, size, &marked);
  for (size_t i = 0; i < marked.size(); ++i)
    if (marked[i]) fp->cells.push_back(uint32_t(i));
}

// The point at fractions (a, b) of cell i (v res + u), in the plane's coordinates.
std::pair<double, double> cell_point(const LightFootprint& fp, uint32_t i, double a, double b) {
  const int u = int(i % uint32_t(fp.res)), v = int(i / uint32_t(fp.res));
  return {-fp.half + (u + a) * fp.cell, -fp.half + (v + b) * fp.cell};
}

}  // namespace

std::optional<LightFootprint> light_footprint(const MajorantGrid& majorants, const Vec3& w, const Vec3& c,
                                              double r) {
  if (majorants.bounds().empty() || !(r > 0.0)) return std::nullopt;
  LightFootprint fp;
  fp.frame = Frame(normalize(w));
  fp.origin = c - fp.frame.n * (2.0 * r);
  fp.half = r;
  // A cell's box projects inside the rectangle of half sides sum_a |e_a| size_a / 2 about its centre's
  // projection, e the frame's axis s or t; the box lies in the sphere, so in the square.
  rasterise(majorants, &fp, [&](const Vec3& lo, const Vec3& size, std::vector<uint8_t>* marked) {
    const Vec3 hs = size * 0.5;
    const auto half = [&](const Vec3& e) {
      return std::abs(e.x) * hs.x + std::abs(e.y) * hs.y + std::abs(e.z) * hs.z;
    };
    const Vec3 q = fp.frame.to_local(lo + hs - c);
    const double hu = half(fp.frame.s), hv = half(fp.frame.t);
    mark(fp, q.x - hu, q.x + hu, q.y - hv, q.y + hv, marked);
  });
  fp.share = fp.area() / (kPi * r * r);
  if (fp.cells.empty() || fp.share >= 0.9) return std::nullopt;
  return fp;
}

std::optional<LightFootprint> point_light_footprint(const MajorantGrid& majorants, const Vec3& light,
                                                    const Vec3& c, double r) {
  const double dist = (c - light).length();
  if (majorants.bounds().empty() || !(r > 0.0) || !(dist > r)) return std::nullopt;
  LightFootprint fp;
  fp.from_point = true;
  fp.frame = Frame((c - light) / dist);
  fp.origin = c;
  fp.light = light;
  fp.dist = dist;
  fp.half = dist * r / std::sqrt(dist * dist - r * r);  // the cone's radius on the plane through c
  // A cell's box projects from the light inside the rectangle about its 8 corners' projections (the box lies
  // in the sphere: in front of the light, and inside the cone).
  rasterise(majorants, &fp, [&](const Vec3& lo, const Vec3& size, std::vector<uint8_t>* marked) {
    double u0 = 1e300, u1 = -1e300, v0 = 1e300, v1 = -1e300;
    for (int k = 0; k < 8; ++k) {
      const Vec3 p = lo + Vec3(k & 1 ? size.x : 0.0, k & 2 ? size.y : 0.0, k & 4 ? size.z : 0.0);
      const Vec3 q = fp.frame.to_local(p - light);
      const double u = q.x * dist / q.z, v = q.y * dist / q.z;
      u0 = std::min(u0, u), u1 = std::max(u1, u), v0 = std::min(v0, v), v1 = std::max(v1, v);
    }
    mark(fp, u0, u1, v0, v1, marked);
  });
  // The cells' solid angle from the light (each by its centre: the count's share only, not the photons' power).
  double omega = 0.0;
  for (const uint32_t i : fp.cells) {
    const auto [u, v] = cell_point(fp, i, 0.5, 0.5);
    const double rho = std::sqrt(u * u + v * v + dist * dist);
    omega += fp.cell * fp.cell * dist / (rho * rho * rho);
  }
  fp.share = omega / (2.0 * kPi * (1.0 - std::sqrt(1.0 - r * r / (dist * dist))));
  if (fp.cells.empty() || fp.share >= 0.9) return std::nullopt;
  return fp;
}

Photon emit_over(const LightFootprint& fp, const Rgb& power, double n, Rng& rng) {
  const double u1 = rng.uniform(), u2 = rng.uniform(), u3 = rng.uniform();
  rng.uniform();  // emit's fourth number, not needed here
  const size_t k = std::min(size_t(u3 * double(fp.cells.size())), fp.cells.size() - 1);
  const auto [x, y] = cell_point(fp, fp.cells[k], u1, u2);
  const Vec3 q = fp.frame.to_world({x, y, 0.0});
  Photon p;
  if (!fp.from_point) {
    p.w = fp.frame.n;
    p.x = fp.origin + q;
    p.power = power * (fp.area() / n);
    return p;
  }
  const Vec3 to = fp.origin + q - fp.light;
  const double rho = to.length();
  p.x = fp.light;
  p.w = to / rho;
  p.power = power * (fp.area() * fp.dist / (rho * rho * rho * n));
  return p;
}

namespace {

// A point of the plane through c normal to w, from emit_with_surfaces' mixture (u0 < kAimedShare: uniform
// on the disc of radius r, else the density h / (2 pi (h^2 + rho^2)^(3/2)) over the plane), `back` behind
// it along w. *area: 1 / the mixture's density there. h: the distance from c along w to the first surface
// (at least r): a ground h below sends the media light from a distance rho along it as h / (h^2 +
// rho^2)^(3/2) (the solid angle of the media times the cosine at the ground), the density itself
// (plane_height).
Vec3 plane_point(const Vec3& c, const Vec3& w, double r, double h, double back, double u0, double u1,
                 double u2, double* area) {
  const double v = 1.0 - u1;  // in (0, 1]
  const double rho = u0 < kAimedShare ? r * std::sqrt(u1) : h * std::sqrt(std::max(0.0, 1.0 / (v * v) - 1.0));
  const double phi = 2.0 * kPi * u2, s = std::sqrt(h * h + rho * rho);
  const double density =
      kAimedShare * (rho < r ? 1.0 / (kPi * r * r) : 0.0) + (1.0 - kAimedShare) * h / (2.0 * kPi * s * s * s);
  *area = 1.0 / density;
  return c - w * back + Frame(w).to_world({rho * std::cos(phi), rho * std::sin(phi), 0.0});
}

// A point or spot light's photon of emit_with_surfaces: the cone towards the media's sphere (cos_aim) with
// probability kAimedShare, else a uniform direction of the light's whole range (a sphere, or the spot's
// cone cos_all = light_cones' cos_spot); the power over the mixture's density.
Photon point_with_surfaces(const Vec3& x, const Vec3& to_c, double cos_aim, double cos_all,
                           const SpotLight* spot, const Rgb& intensity, double n, double u0, double u1,
                           double u2) {
  const Vec3 axis_all = spot ? spot->direction : Vec3(0, 0, 1);
  Photon p;
  p.x = x;
  p.w = u0 < kAimedShare ? spherical_direction(1.0 - u1 * (1.0 - cos_aim), 2.0 * kPi * u2, to_c)
                         : spherical_direction(1.0 - u1 * (1.0 - cos_all), 2.0 * kPi * u2, axis_all);
  const bool in_aim = dot(p.w, to_c) >= cos_aim;
  const bool in_all = !spot || dot(p.w, spot->direction) >= cos_all;
  const double pdf = kAimedShare * (in_aim ? 1.0 / (2.0 * kPi * (1.0 - cos_aim)) : 0.0) +
                     (1.0 - kAimedShare) * (in_all ? 1.0 / (2.0 * kPi * (1.0 - cos_all)) : 0.0);
  const double falloff = spot ? (in_all ? spot_falloff(*spot, dot(p.w, spot->direction)) : 0.0) : 1.0;
  const double aim = 2.0 * kPi * (1.0 - cos_aim);  // emit's solid angle
  p.power = intensity * (aim / n);
  p.weight = pdf > 0.0 ? falloff / (pdf * aim) : 0.0;
  return p;
}

}  // namespace

double plane_height(const SceneContext& ctx, const Vec3& c, const Vec3& w, double r) {
  SurfaceHit hit;
  return ctx.surfaces.intersect(c, w, std::numeric_limits<double>::infinity(), &hit) ? std::max(r, hit.t) : r;
}

SurfaceEmission surface_emission(const SceneContext& ctx, const Vec3& c, double r) {
  SurfaceEmission e;
  e.back = photon_start_distance(ctx, c, r);
  for (const Light& light : ctx.lights) {
    const auto* d = std::get_if<DirectionalLight>(&light);
    e.plane_h.push_back(d ? plane_height(ctx, c, normalize(d->direction), r) : 0.0);
  }
  return e;
}

double photon_start_distance(const SceneContext& ctx, const Vec3& c, double r) {
  const Bounds& sb = ctx.surfaces.bounds();
  double reach = 0.0;
  if (!sb.empty())
    for (int k = 0; k < 8; ++k)
      reach = std::max(
          reach, (Vec3(k & 1 ? sb.hi.x : sb.lo.x, k & 2 ? sb.hi.y : sb.lo.y, k & 4 ? sb.hi.z : sb.lo.z) - c)
                     .length());
  return 2.0 * r + reach;
}

Photon emit_with_surfaces(const SceneContext& ctx, size_t source, const Vec3& c, double r,
                          const SurfaceEmission& se, double n, Rng& rng) {
  const double u0 = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform(), u3 = rng.uniform(),
               u4 = rng.uniform();
  double area = 0.0;
  Photon p;
  if (source < ctx.lights.size()) {
    const Light& light = ctx.lights[source];
    if (const auto* d = std::get_if<DirectionalLight>(&light)) {
      p.w = normalize(d->direction);
      NIMBUS_DCHECK(source < se.plane_h.size());  // se: surface_emission(ctx, c, r)
      p.x = plane_point(c, p.w, r, se.plane_h[source], se.back, u0, u3, u4, &area);
      p.power = d->irradiance * (kPi * r * r / n);  // emit's, over the weight area / (pi r^2)
      p.weight = area / (kPi * r * r);
      return p;
    }
    const auto* pt = std::get_if<PointLight>(&light);
    const auto* spot = std::get_if<SpotLight>(&light);
    if (!(pt || spot)) return emit(ctx, source, c, r, n, rng);
    const Vec3 x = pt ? pt->position : spot->position;
    const auto [dist, cos_aim, cos_spot] = light_cones(x, spot, c, r);
    if (dist <= r || cos_spot > cos_aim) return emit(ctx, source, c, r, n, rng);
    return point_with_surfaces(x, (c - x) / dist, cos_aim, cos_spot, spot,
                               pt ? pt->intensity : spot->intensity, n, u0, u1, u2);
  }
  // The environment: its direction as emit draws it, then a point of the plane.
  double pdf = 1.0 / (4.0 * kPi);
  Rgb radiance = ctx.environment;
  if (ctx.env_map) {
    const Vec3 wi = env_photon_direction(ctx, u1, u2, &pdf);
    p.w = -wi;
    radiance = ctx.environment_radiance(wi);
  } else {
    p.w = spherical_direction(1.0 - 2.0 * u1, 2.0 * kPi * u2, Vec3(0, 0, 1));
  }
  p.x = plane_point(c, p.w, r, plane_height(ctx, c, p.w, r), se.back, u0, u3, u4, &area);
  p.power = pdf > 0.0 ? radiance * (kPi * r * r / (pdf * n)) : Rgb(0.0);
  p.weight = area / (kPi * r * r);
  return p;
}

bool grey_media(const SceneContext& ctx) {
  bool grey = true;
  for (int i = 0; i < ctx.media.count(); ++i) {
    const Medium& m = ctx.media.medium(i);
    grey = grey && m.sigma_s.x == m.sigma_s.y && m.sigma_s.y == m.sigma_s.z && m.sigma_a.x == m.sigma_a.y &&
           m.sigma_a.y == m.sigma_a.z;
  }
  return grey;
}

namespace {

// The batches' tallies and the scale of each (planned / traced photons).
struct TracedBatches {
  ZeroedFloats tallies;  // all batches' tallies in one block (their views in batch[b].tally)
  std::vector<PhotonBatch> batch;
  std::vector<double> scale;
};

TracedBatches run_batches(size_t total, uint64_t stream_seed, size_t tally_size,
                          const TracePhoton& trace_photon, uint64_t* rejection_failures) {
  // One block for all the batches, each tally from a cache line of its own: the kernel zeroes whole huge
  // pages, so eight tallies of a third of a page each would cost eight pages apart and cost three here.
  constexpr size_t kLineFloats = 64 / sizeof(float);
  const size_t pitch = (tally_size + kLineFloats - 1) / kLineFloats * kLineFloats;
  ZeroedFloats tallies(pitch * kPhotonBatches);
  std::vector<PhotonBatch> batch(kPhotonBatches);
  std::vector<double> batch_scale(kPhotonBatches, 1.0);
  for (int b = 0; b < kPhotonBatches; ++b) batch[b].tally = {tallies.data() + pitch * size_t(b), tally_size};
  tbb::parallel_for(0, kPhotonBatches, [&](int b) {
    PhotonBatch& pb = batch[b];
    const size_t begin = total * size_t(b) / kPhotonBatches, end = total * size_t(b + 1) / kPhotonBatches;
    const double budget = kEventsPerPhoton * double(end - begin);
    size_t j = begin;
    for (; j < end && pb.collisions <= budget; ++j) {
      Rng rng(stream_seed, j);
      trace_photon(j, rng, pb);
    }
    batch_scale[b] = j > begin ? double(end - begin) / double(j - begin) : 1.0;
  });
  for (const PhotonBatch& pb : batch) *rejection_failures += pb.rejection_failures;
  return {std::move(tallies), std::move(batch), std::move(batch_scale)};
}

}  // namespace

FloatArray trace_photons(size_t total, uint64_t stream_seed, size_t tally_size, double scale,
                         const TracePhoton& trace_photon, uint64_t* rejection_failures) {
  // (Named, not a structured binding: clang 14 cannot capture one in the lambdas below.)
  const TracedBatches traced = run_batches(total, stream_seed, tally_size, trace_photon, rejection_failures);
  const std::vector<PhotonBatch>& batch = traced.batch;
  const std::vector<double>& batch_scale = traced.scale;
  // Sum the batches in order (the same sum for every thread count).
  FloatArray sum(tally_size);
  tbb::parallel_for(size_t(0), tally_size, [&](size_t n) {
    double s = 0.0;
    for (int b = 0; b < kPhotonBatches; ++b) s += batch_scale[b] * batch[b].tally[n];
    sum[n] = float(s * scale);
  });
  return sum;
}

FloatArray trace_photons_folded(size_t total, uint64_t stream_seed, size_t tally_size, double scale,
                                const TallyFold& fold, const TracePhoton& trace_photon,
                                uint64_t* rejection_failures, FloatArray* per_batch) {
  // (Named, not a structured binding: clang 14 cannot capture one in the lambdas below.)
  const TracedBatches traced = run_batches(total, stream_seed, tally_size, trace_photon, rejection_failures);
  const std::vector<PhotonBatch>& batch = traced.batch;
  const std::vector<double>& batch_scale = traced.scale;
  // Fold the batches node by node, in order (the same sum for every thread count).
  const int k = fold.out_floats;
  FloatArray sum(fold.nodes * size_t(k));
  const size_t probes = per_batch ? fold.probes.size() : 0;
  if (per_batch) *per_batch = FloatArray(fold.nodes * kPhotonBatches * probes);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, fold.nodes), [&](const tbb::blocked_range<size_t>& r) {
    std::vector<double> acc(static_cast<size_t>(k)), before(probes);
    for (size_t n = r.begin(); n != r.end(); ++n) {
      std::fill(acc.begin(), acc.end(), 0.0);
      for (int b = 0; b < kPhotonBatches; ++b) {
        for (size_t p = 0; p < probes; ++p) before[p] = acc[size_t(fold.probes[p])];
        fold.fold(batch[b].tally.data(), n, batch_scale[b], acc.data());
        float* share = probes ? &(*per_batch)[(n * kPhotonBatches + size_t(b)) * probes] : nullptr;
        for (size_t p = 0; p < probes; ++p)
          share[p] = float((acc[size_t(fold.probes[p])] - before[p]) * scale);
      }
      for (int i = 0; i < k; ++i) sum[n * k + i] = float(acc[i] * scale);
    }
  });
  return sum;
}

double majorant_share(const SceneMedia& media, const std::function<double(int)>& kept) {
  double share = media.count() > 0 ? 0.0 : 1.0;
  for (int i = 0; i < media.count(); ++i) {
    const Medium& m = media.medium(i);
    const double full = max_component(m.sigma_s + m.sigma_a);
    if (!(full > 0.0)) continue;
    const double k = std::clamp(kept(i), 0.0, 1.0);
    share = std::max(share, std::min(1.0, max_component(m.sigma_a + m.sigma_s * k) / full));
  }
  return share;
}

}  // namespace nimbus
