// What the camera sees of the visible area lights, and the area lights' transmittance for the
// integrators that keep a shadow map per light (single with shadow maps, octave, mfs): they sample a
// point of the light at every march sample and march towards it, because one grid of transmittance
// towards the light's centre would give every soft shadow the hard edge of a point light's.
#pragma once

#include "core/ray.h"
#include "core/rng.h"
#include "integrators/integrator.h"
#include "scene/context.h"

namespace nimbus {

// The radiance of the visible sphere and rectangle lights along a camera ray, each through the
// transmittance in front of it (surfaces block it; media by ratio tracking, unbiased, or with
// march_step > 0 a midpoint march as in shadow_transmittance). Lights do not occlude one another.
// Consumes random numbers only for lights the ray meets. A transient render (timed non-null) also records
// each light's part with its distance from the camera (the ray's origin).
Rgb visible_area_lights(const SceneContext& ctx, const Ray& ray, Rng& rng, double march_step = 0.0,
                        std::vector<TimedContribution>* timed = nullptr);

// True when some light of ctx is a visible area light (integrators skip the call otherwise).
bool has_visible_area_lights(const SceneContext& ctx);

// One midpoint march from p along w over (0, tmax) in steps of tau_step optical depth against the
// majorant (as marched_transmittance) giving both the transmittance of the full extinction and of the
// extinction less each medium's peak_fraction of its scattering (reduced_sigma_t): `mfs`'s two
// transmittances to a sampled point of an area light, for the price of one march.
void marched_full_and_reduced(const SceneContext& ctx, const Vec3& p, const Vec3& w, double tmax,
                              double tau_step, const std::vector<double>& peak_fraction, Rgb* T_full,
                              Rgb* T_reduced);

// The same two in closed form where the scene's media are one constant-density sphere or box
// (ctx.analytic active, one medium): its chord along w over (0, tmax). False (nothing written) for any
// other scene.
bool chord_full_and_reduced(const SceneContext& ctx, const Vec3& p, const Vec3& w, double tmax,
                            const std::vector<double>& peak_fraction, Rgb* T_full, Rgb* T_reduced);

}  // namespace nimbus
