// Integrators: an open set behind one virtual call per camera ray. Each holds what it precomputed for
// the scene (shadow maps, photon grids); Li() is called concurrently from many threads. The driver
// (src/render/render.cpp) makes the camera rays and owns the film; the registry
// (integrators/registry.h) parses each integrator's settings and constructs it.
#pragma once

#include <limits>
#include <nlohmann/json.hpp>
#include <vector>

#include "core/math.h"
#include "core/ray.h"
#include "core/rng.h"
#include "scene/context.h"

namespace nimbus {

// A stretch [t0, t1] of a camera ray (t1 == t0: a point) and what it adds to the pixel as seen from the
// camera: radiance L (already attenuated by the transmittance in front of it) and alpha, the mean
// transmittance it removes. A deep image is made of them (src/render/deep.h).
struct DeepSegment {
  double t0 = 0.0, t1 = 0.0;
  Rgb L{0.0};
  double alpha = 0.0;
};

// A part of a camera sample's radiance and the total length s of its path, from where the light left
// its source (a light's sampled point, an emitting medium's point, or for a distant light the plane of
// integrators/path_clock.h) to the camera: a transient render bins the parts by s (src/render/time_film.h).
// `background`: the environment seen directly (a transparent film leaves it out).
struct TimedContribution {
  double s = 0.0;
  Rgb L{0.0};
  bool background = false;
};

// What one camera sample tells the film beyond its radiance: the compositing layers. Every field is a
// one-sample estimate whose pixel mean is the layer (an integrator may fill it with an unbiased
// stochastic estimate, e.g. an escape indicator for a transmittance). Radiances are parts of Li's
// return value, never additions to it.
struct CameraSample {
  // The environment seen directly along the camera ray: T_escape * environment radiance. A transparent
  // film subtracts it from the beauty.
  Rgb background{0.0};
  // Transmittance of the camera ray to the background (0 where it ends on a surface or a holdout).
  Rgb escape_transmittance{1.0};
  // Transmittance of the camera ray to a holdout it ends on (0 otherwise): the part of the pixel the
  // holdout cuts out. Alpha = 1 - mean(escape_transmittance) - mean(holdout_transmittance) on a
  // transparent film (or one without an environment); 1 - mean(holdout_transmittance) otherwise.
  Rgb holdout_transmittance{0.0};
  // Distance along the camera ray to the first surface or, in a volume, to where the ray's
  // transmittance (mean over channels) falls to one half; infinity where neither.
  double depth = std::numeric_limits<double>::infinity();
  // Unscattered and single-scattered light (the camera ray's first interaction lit directly); the
  // `indirect` layer is Li minus this.
  Rgb direct{0.0};
  // For denoisers: the first surface's albedo, or in a volume the single-scattering albedo where the
  // depth is taken, and the shading normal of the first surface (0 in a volume).
  Rgb albedo{0.0};
  Vec3 normal{0.0, 0.0, 0.0};

  // Set by the driver (the film layers work; not layers themselves). depth_wanted: the film keeps
  // depth or albedo (an integrator may skip work done only for them: pathtrace's depth march). deep:
  // where an integrator appends the camera ray's DeepSegments, front to back, whose L sum to
  // Li - background and whose alpha sum to 1 - mean(escape_transmittance) - mean(holdout_transmittance);
  // null when no deep image is made.
  bool depth_wanted = true;
  std::vector<DeepSegment>* deep = nullptr;
  // A transient render (film.time_bins; pathtrace only): where an integrator appends every part of Li
  // with its path length; the parts sum to Li (up to rounding). Null otherwise.
  std::vector<TimedContribution>* timed = nullptr;
};

class Integrator {
 public:
  virtual ~Integrator() = default;
  // Radiance arriving at ray.o from direction -ray.d (light travelling against the ray). With a
  // non-null `sample` (camera rays of a film with layers), also fills the compositing layers.
  virtual Rgb Li(const Ray& ray, Rng& rng, CameraSample* sample = nullptr) const = 0;
  // The integrator's own settings as the JSON fields of its integrator block, with "auto" choices
  // resolved: written into the image header, so that an image says exactly how it was made.
  virtual nlohmann::json settings_json() const = 0;
  // Samples per pixel sample at pixels a hard outline crosses (scene/edges.h); the pixels beside them take
  // a quarter of it (at least 1). Their estimates stay the mean of independent samples spread over the
  // pixel, so nothing is biased: they only get more of them. 1: none.
  virtual int edge_samples() const { return 1; }
};

}  // namespace nimbus
