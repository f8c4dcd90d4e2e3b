// Surfaces through Embree 3 (scene/surfaces.h). Triangles for meshes, rectangles and boxes; spheres as
// user geometry intersected analytically in double precision (exact silhouettes at any size).
#include "scene/surfaces.h"

#include <embree3/rtcore.h>
#include <fmt/format.h>

#include <cmath>

#include "nimbus/error.h"
#include "scene/mesh.h"

namespace nimbus {

namespace {

// A sphere in its own space, placed in the world by `to_world` (any invertible affine map: an ellipsoid).
struct SphereData {
  Vec3 center;
  double radius;
  Transform to_world, to_local;
  bool identity = true;
  Bounds world_bounds;
};

// What a hit on an Embree geometry means: the scene's surface and, for meshes, their vertex normals.
struct GeometryInfo {
  int surface = -1;
  const TriangleMesh* mesh = nullptr;  // set when the mesh has vertex normals
  const SphereData* sphere = nullptr;
};

void sphere_bounds(const RTCBoundsFunctionArguments* args) {
  const auto* s = static_cast<const SphereData*>(args->geometryUserPtr);
  RTCBounds* b = args->bounds_o;
  // Rounded outwards so that the float box contains the double sphere.
  const Bounds& w = s->world_bounds;
  const float pad = float(1e-6 * (max_abs_component(w.lo) + max_abs_component(w.hi)));
  b->lower_x = float(w.lo.x) - pad;
  b->lower_y = float(w.lo.y) - pad;
  b->lower_z = float(w.lo.z) - pad;
  b->upper_x = float(w.hi.x) + pad;
  b->upper_y = float(w.hi.y) + pad;
  b->upper_z = float(w.hi.z) + pad;
}

// The nearest root of |o + t d - c| = r with t in (tnear, tfar), d not necessarily unit.
bool sphere_root(const SphereData& s, const Vec3& o, const Vec3& d, double tnear, double tfar, double* t) {
  const double dd = dot(d, d);
  const Vec3 oc = o - s.center;
  const double b = dot(oc, d) / dd;
  // The discriminant from the closest approach (stable for small spheres far away).
  const Vec3 closest = oc - d * b;
  const double disc = s.radius * s.radius - dot(closest, closest);
  if (disc < 0.0) return false;
  const double h = std::sqrt(disc / dd);
  const double t0 = -b - h, t1 = -b + h;
  if (t0 > tnear && t0 < tfar) {
    *t = t0;
    return true;
  }
  if (t1 > tnear && t1 < tfar) {
    *t = t1;
    return true;
  }
  return false;
}

void sphere_intersect(const RTCIntersectFunctionNArguments* args) {
  if (!args->valid[0]) return;
  const auto* s = static_cast<const SphereData*>(args->geometryUserPtr);
  auto* rh = reinterpret_cast<RTCRayHit*>(args->rayhit);  // N == 1: rtcIntersect1 only
  RTCRay& r = rh->ray;
  Vec3 o(r.org_x, r.org_y, r.org_z), d(r.dir_x, r.dir_y, r.dir_z);
  if (!s->identity) {  // the same t in the sphere's space: the map is affine
    o = s->to_local.point(o);
    d = s->to_local.vector(d);
  }
  double t;
  if (!sphere_root(*s, o, d, r.tnear, r.tfar, &t)) return;
  Vec3 n = o + d * t - s->center;
  if (!s->identity) n = s->to_world.normal(n);  // the world normal: the inverse transpose
  r.tfar = float(t);
  rh->hit.Ng_x = float(n.x);
  rh->hit.Ng_y = float(n.y);
  rh->hit.Ng_z = float(n.z);
  rh->hit.u = rh->hit.v = 0.0f;
  rh->hit.primID = args->primID;
  rh->hit.geomID = args->geomID;
  rh->hit.instID[0] = args->context->instID[0];
}

void sphere_occluded(const RTCOccludedFunctionNArguments* args) {
  if (!args->valid[0]) return;
  const auto* s = static_cast<const SphereData*>(args->geometryUserPtr);
  auto* r = reinterpret_cast<RTCRay*>(args->ray);
  Vec3 o(r->org_x, r->org_y, r->org_z), d(r->dir_x, r->dir_y, r->dir_z);
  if (!s->identity) {
    o = s->to_local.point(o);
    d = s->to_local.vector(d);
  }
  double t;
  if (sphere_root(*s, o, d, r->tnear, r->tfar, &t)) r->tfar = -std::numeric_limits<float>::infinity();
}

// Embree's single-precision ray o + t d, t in [0, tmax) (an infinite tmax stays infinite).
RTCRay embree_ray(const Vec3& o, const Vec3& d, double tmax) {
  RTCRay r;
  r.org_x = float(o.x);
  r.org_y = float(o.y);
  r.org_z = float(o.z);
  r.dir_x = float(d.x);
  r.dir_y = float(d.y);
  r.dir_z = float(d.z);
  r.tnear = 0.0f;
  r.tfar = tmax < 3e38 ? float(tmax) : std::numeric_limits<float>::infinity();
  r.mask = ~0u;
  r.flags = 0;
  r.time = 0.0f;
  r.id = 0;
  return r;
}

// The triangles of a rectangle and of a box (two per face).
void rectangle_triangles(const RectangleSurface& r, TriangleMesh* m) {
  const Vec3 n = normalize(r.normal);
  const Vec3 v = normalize(r.up - n * dot(r.up, n));
  const Vec3 u = cross(n, v);  // so that u x v = n
  const Vec3 hu = u * (0.5 * r.width), hv = v * (0.5 * r.height);
  const uint32_t base = uint32_t(m->vertex_count());
  for (const Vec3& p : {r.center - hu - hv, r.center + hu - hv, r.center + hu + hv, r.center - hu + hv})
    for (int c = 0; c < 3; ++c) m->positions.push_back(float(p[c]));
  for (uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) m->indices.push_back(base + i);
}

void box_triangles(const BoxSurface& b, TriangleMesh* m) {
  const Vec3 c = (b.min + b.max) * 0.5, h = (b.max - b.min) * 0.5;
  for (int a = 0; a < 3; ++a) {
    for (double s : {-1.0, 1.0}) {
      Vec3 n(0.0, 0.0, 0.0), up(0.0, 0.0, 0.0);
      n[a] = s;
      up[(a + 1) % 3] = 1.0;
      RectangleSurface face;
      face.normal = n;
      face.up = up;
      face.center = c + n * h[a];
      face.height = 2.0 * h[(a + 1) % 3];
      face.width = 2.0 * h[(a + 2) % 3];
      rectangle_triangles(face, m);
    }
  }
}

// A mesh's vertices (and vertex normals) carried into the world.
TriangleMesh transformed(const TriangleMesh& m, const Transform& xf) {
  TriangleMesh out = m;
  for (size_t v = 0; v < m.vertex_count(); ++v) {
    const Vec3 p = xf.point(m.position(v));
    for (int c = 0; c < 3; ++c) out.positions[3 * v + c] = float(p[c]);
    if (m.normals.empty()) continue;
    const Vec3 n = xf.normal(m.normal(v));
    for (int c = 0; c < 3; ++c) out.normals[3 * v + c] = float(n[c]);
  }
  return out;
}

// The world box of a transformed sphere: for world = A x + b, the ellipsoid's half extent along axis k
// is r |row k of A|.
Bounds sphere_world_bounds(const SphereSurface& s, const Transform& xf) {
  const Vec3 c = xf.point(s.center);
  Vec3 h;
  for (int k = 0; k < 3; ++k) {
    const auto& row = xf.matrix()[k];
    h[k] = s.radius * std::sqrt(row[0] * row[0] + row[1] * row[1] + row[2] * row[2]);
  }
  Bounds b;
  b.extend(c - h);
  b.extend(c + h);
  return b;
}

}  // namespace

struct SceneSurfaces::Embree {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  std::vector<GeometryInfo> geometry;    // by Embree geometry id
  std::vector<TriangleMesh> own_meshes;  // rectangles and boxes
  std::vector<SphereData> spheres;
  ~Embree() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
  void check(const char* what) const {
    const RTCError e = rtcGetDeviceError(device);
    if (e != RTC_ERROR_NONE) throw Error(fmt::format("Embree: {} failed (error {})", what, int(e)));
  }
  void attach(RTCGeometry g, GeometryInfo info) {
    rtcCommitGeometry(g);
    const unsigned id = rtcAttachGeometry(scene, g);
    rtcReleaseGeometry(g);
    if (geometry.size() <= id) geometry.resize(id + 1);
    geometry[id] = info;
  }
  void add_triangles(const TriangleMesh& m, int surface) {
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                          3 * sizeof(float), m.vertex_count()));
    auto* i = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                             3 * sizeof(uint32_t), m.triangle_count()));
    check("allocating a triangle geometry");
    std::copy(m.positions.begin(), m.positions.end(), v);
    std::copy(m.indices.begin(), m.indices.end(), i);
    attach(g, {surface, m.normals.empty() ? nullptr : &m, nullptr});
  }
  void add_sphere(const SphereData* s, int surface) {
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
    rtcSetGeometryUserPrimitiveCount(g, 1);
    rtcSetGeometryUserData(g, const_cast<SphereData*>(s));
    rtcSetGeometryBoundsFunction(g, sphere_bounds, nullptr);
    rtcSetGeometryIntersectFunction(g, sphere_intersect);
    rtcSetGeometryOccludedFunction(g, sphere_occluded);
    attach(g, {surface, nullptr, s});
  }
};

SceneSurfaces::SceneSurfaces(const std::vector<Surface>& surfaces) : surfaces_(surfaces) {
  if (surfaces_.empty()) return;
  embree_ = std::make_unique<Embree>();
  Embree& e = *embree_;
  e.device = rtcNewDevice(nullptr);
  if (!e.device) throw Error("Embree: cannot create a device");
  e.scene = rtcNewScene(e.device);
  rtcSetSceneFlags(e.scene, RTC_SCENE_FLAG_ROBUST);
  // Reserved up front: geometries keep pointers into these vectors.
  e.own_meshes.reserve(surfaces_.size());
  e.spheres.reserve(surfaces_.size());
  for (int i = 0; i < int(surfaces_.size()); ++i) {
    const SurfaceShape& shape = surfaces_[i].shape;
    const Transform& xf = surfaces_[i].transform;
    if (const auto* s = std::get_if<SphereSurface>(&shape)) {
      SphereData sd{s->center, s->radius, xf, xf.inverse(), xf.is_identity(), Bounds{}};
      sd.world_bounds = sphere_world_bounds(*s, xf);
      e.spheres.push_back(sd);
      e.add_sphere(&e.spheres.back(), i);
      bounds_.extend(sd.world_bounds);
      continue;
    }
    const TriangleMesh* mesh = nullptr;
    if (const auto* m = std::get_if<MeshSurface>(&shape); m && xf.is_identity()) {
      mesh = m->data.get();
    } else if (m) {
      e.own_meshes.push_back(transformed(*m->data, xf));
      mesh = &e.own_meshes.back();
    } else {
      e.own_meshes.emplace_back();
      if (const auto* r = std::get_if<RectangleSurface>(&shape))
        rectangle_triangles(*r, &e.own_meshes.back());
      if (const auto* b = std::get_if<BoxSurface>(&shape)) box_triangles(*b, &e.own_meshes.back());
      if (!xf.is_identity()) e.own_meshes.back() = transformed(e.own_meshes.back(), xf);
      mesh = &e.own_meshes.back();
    }
    e.add_triangles(*mesh, i);
    for (size_t v = 0; v < mesh->vertex_count(); ++v) bounds_.extend(mesh->position(v));
  }
  rtcCommitScene(e.scene);
  e.check("building the surfaces' BVH");
}

SceneSurfaces::~SceneSurfaces() = default;

bool SceneSurfaces::intersect(const Vec3& o, const Vec3& d, double tmax, SurfaceHit* hit) const {
  if (!embree_) return false;
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rh;
  rh.ray = embree_ray(o, d, tmax);
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(embree_->scene, &context, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
  const GeometryInfo& info = embree_->geometry[rh.hit.geomID];
  hit->t = rh.ray.tfar;
  hit->p = o + d * hit->t;
  Vec3 ng = normalize(Vec3(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z));
  if (info.sphere && info.sphere->identity) ng = normalize(hit->p - info.sphere->center);  // double precision
  if (dot(ng, d) > 0.0) ng = -ng;
  hit->ng = ng;
  hit->ns = ng;
  if (info.mesh) {
    const TriangleMesh& m = *info.mesh;
    const uint32_t* tri = &m.indices[3 * size_t(rh.hit.primID)];
    const double u = rh.hit.u, v = rh.hit.v;
    const Vec3 n = m.normal(tri[0]) * (1.0 - u - v) + m.normal(tri[1]) * u + m.normal(tri[2]) * v;
    const double len = length(n);
    if (len > 0.0) hit->ns = dot(n, ng) >= 0.0 ? n / len : -n / len;
  }
  hit->surface = info.surface;
  return true;
}

bool SceneSurfaces::occluded(const Vec3& o, const Vec3& d, double tmax) const {
  if (!embree_) return false;
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRay r = embree_ray(o, d, tmax);
  rtcOccluded1(embree_->scene, &context, &r);
  return r.tfar < 0.0f;
}

Vec3 SceneSurfaces::offset(const SurfaceHit& hit, const Vec3& d) {
  const double eps = 1e-5 * (max_abs_component(hit.p) + hit.t);
  return hit.p + (dot(hit.ng, d) >= 0.0 ? hit.ng : -hit.ng) * eps;
}

}  // namespace nimbus
