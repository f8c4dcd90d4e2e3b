// The procedural cumulus of the built-in demo: a noise-displaced union of blobs, deterministic
// from a seed. Density in [0, 1] at a point given in units of the cloud's radius (|p| <= 1 holds
// all of it).
#pragma once

#include <cstdint>

#include "core/math.h"

namespace nimbus {

double procedural_cloud_density(const Vec3& p, uint32_t seed);

// Gradient noise in [-1, 1] (Perlin's improved noise construction, hashed lattice gradients).
double gradient_noise(const Vec3& p, uint32_t seed);
// Fractal sum of `octaves` octaves of gradient noise, roughly in [-1, 1].
double fbm(const Vec3& p, uint32_t seed, int octaves);

}  // namespace nimbus
