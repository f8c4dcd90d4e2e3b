// The sphere and rectangle area lights (docs/scene-format.md, "Spot, sphere and rectangle lights"):
// sampling a connection from a point for next-event estimation, what a ray sees of a visible light, and
// where a photon leaves one. Physics as free functions; lights.h's sample_light dispatches here.
//
// A sphere light emits radiance L outward from every point of its surface (power 4 pi^2 r^2 L); it is
// sampled by the solid angle of the cap seen from the shading point (uniform in the cone, pdf
// 1 / (2 pi (1 - cos_max))), exact for any distance. A rectangle light emits L from one side, along its
// normal (power pi A L); it is sampled uniformly in the solid angle it subtends (Urena et al. 2013; by
// area, pdf d^2 / (A cos_l), where that solid angle is below 1e-3 sr). Neither
// occludes anything: they are not in the surfaces' scene.
#pragma once

#include "core/math.h"
#include "nimbus/scene.h"

namespace nimbus {

struct LightSample;

// A connection from p to a point of the light chosen by (u1, u2). False when p sees nothing of it (p
// inside the sphere; behind the rectangle's emitting side or on its plane).
bool sample_sphere_light(const SphereLight& s, const Vec3& p, double u1, double u2, LightSample* out);
bool sample_rectangle_light(const RectangleLight& r, const Vec3& p, double u1, double u2, LightSample* out);

// The rectangle's edge directions: width along normal x up, height along up (both unit).
inline Vec3 rectangle_width_axis(const RectangleLight& r) { return normalize(cross(r.normal, r.up)); }

// The nearest point in (0, tmax) where the ray o + t d meets the emitting side of a light (the sphere
// from outside; the rectangle against its normal): true with *t and the radiance *L it sends back along
// -d. Ignores `visible` (the caller asks only for visible lights).
bool hit_area_light(const Light& light, const Vec3& o, const Vec3& d, double tmax, double* t, Rgb* L);

// Where a photon leaves an area light, for `count` photons of that light: a uniform point of the
// emitting surface and a cosine-weighted direction around its outward normal (u1, u2: the point; u3,
// u4: the direction); *power = L pi A / count. False for other lights.
bool emit_area_photon(const Light& light, double count, double u1, double u2, double u3, double u4, Vec3* x,
                      Vec3* w, Rgb* power);

}  // namespace nimbus
