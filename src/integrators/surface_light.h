// Light at opaque surfaces, shared by the integrators: shadow rays that see surfaces and media, the
// direct light on a diffuse surface point, and the light leaving a surface that a camera ray ends on.
#pragma once

#include <functional>

#include "integrators/integrator.h"
#include "integrators/path_clock.h"
#include "scene/surfaces.h"

namespace nimbus {

// The optical-depth step of the marched shadows on surfaces (octave, mfs, single with shadow maps):
// midpoint error O(step^2) in smooth media, well under the noise of a few spp.
inline constexpr double kSurfaceShadowStep = 0.1;

// The environment image's light on a diffuse surface point per unit albedo (cosine-weighted irradiance
// / pi): a map-sampled and a cosine-sampled direction by MIS (integrators/env_light.h). ctx.env_map set.
Rgb surface_env_map_light(const SceneContext& ctx, const SurfaceHit& hit, Rng& rng, double march_step = 0.0);

// Transmittance from p along w (unit) over (0, tmax): 0 when a surface blocks the way, else the media's
// by ratio tracking (unbiased; march_step 0) or by a deterministic midpoint march with steps of
// march_step optical depth (smooth shadows for the integrators that march: octave, mfs).
Rgb shadow_transmittance(const SceneContext& ctx, const Vec3& p, const Vec3& w, double tmax, Rng& rng,
                         double march_step = 0.0);

// (albedo / pi) times the cosine-weighted irradiance at a diffuse surface point from every directional,
// point, spot and area light (light sampling, one sample each), through shadow_transmittance. hit.ns
// faces the viewer; the surface is two-sided, lit on the viewer's side only.
// A transient render (timed non-null) also records each light's part with its connection's length.
Rgb surface_direct_light(const SceneContext& ctx, const SurfaceHit& hit, const Rgb& albedo, Rng& rng,
                         double march_step = 0.0, const PathClock* timed = nullptr);

// The radiance that leaves a surface point towards the ray that found it, for the integrators that march
// the camera ray (single, octave, mfs): 0 for a holdout; for a diffuse surface its direct light plus
// albedo times the radiance arriving along one cosine-sampled direction (weight albedo: (albedo / pi)
// cos / (cos / pi)). `gather(ray)` is that radiance as the integrator itself computes it along a ray (the
// medium's scattered light, the environment and surfaces behind, with their direct light); without a
// gather (nullptr), only the environment through the media is gathered. An environment image is taken by
// surface_env_map_light (MIS) in both cases, and the gathered ray's own escape then leaves it out.
using GatherFn = std::function<Rgb(const Ray&)>;
// *direct_part (when given) receives the lights' direct part of the result. A transient render (timed
// non-null; no gather, no environment image) also records each part with its light connection's length.
Rgb surface_radiance(const SceneContext& ctx, const SurfaceHit& hit, Rng& rng, const GatherFn* gather,
                     Rgb* direct_part = nullptr, double march_step = 0.0, const PathClock* timed = nullptr);

// The light at the end of a marched ray (direction d), seen through its transmittance T: the surface it
// ends on (hit, through surface_radiance with `gather`; its layers recorded into a non-null sample, with a
// deep segment for a diffuse surface), or with hit == nullptr the environment along d. *direct_part (when given)
// receives the surface's direct light as seen through T (0 for the environment).
// march_step: as for shadow_transmittance.
Rgb ray_end_radiance(const SceneContext& ctx, const SurfaceHit* hit, const Vec3& d, const Rgb& T, Rng& rng,
                     CameraSample* sample, const GatherFn* gather, Rgb* direct_part = nullptr,
                     double march_step = 0.0);

// The compositing layers of a camera ray ending on a surface, seen through transmittance T: no escape,
// the holdout's transmittance, the shading normal, and depth and albedo unless the media in front
// already set them (their transmittance fell to one half before the surface).
void record_surface_hit(const SceneContext& ctx, const SurfaceHit& hit, const Rgb& T, CameraSample* sample);

}  // namespace nimbus
