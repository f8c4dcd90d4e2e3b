// The one photon tracer behind the grids `mfs` fills before it renders (the scatter grid and the beam
// grid): emission from the lights and the environment, a fixed number of batches (so the grids do not
// depend on the thread count), the work budget, and the walker. The walker is written once, after the
// tracking kernel (integrators/tracking.h): it flies a photon from collision to collision (delta
// tracking against the majorant grid with the caller's density of real collisions) and calls back per
// flight (to deposit it) and per real collision (to weight, end or turn the photon). What a collision
// is, what a flight deposits and how a photon turns belong to the grids.
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <type_traits>
#include <vector>

#include "core/check.h"
#include "core/math.h"
#include "core/rng.h"
#include "core/zeroed_floats.h"
#include "integrators/integrator.h"
#include "integrators/tracking.h"
#include "media/media.h"

namespace nimbus {

inline constexpr int kPhotonBatches = 8;          // fixed: the grids must not depend on the thread count
inline constexpr int kMaxPhotonEvents = 1 << 14;  // photons are ended after this many real collisions
// Work budget: a batch stops starting photons once its collisions exceed this many per photon of the
// batch, and its deposits are scaled by planned / traced photons (optically very thick media would
// otherwise take hours; below the budget nothing changes).
inline constexpr double kEventsPerPhoton = 512.0;
// Tries of a rejection-sampled scatter direction (sample_by_rejection) before it gives up.
inline constexpr int kMaxRejectionTries = 10000;

struct Photon {
  Vec3 x, w;
  Rgb power;
  // The weight the photon starts with (its power is power x weight). The grids' roulettes end photons
  // whose weight falls below 0.1: a photon of emit_with_surfaces' far plane starts heavy, and must keep
  // that weight through its bounce towards the media rather than be raised to 0.1 of a larger power.
  double weight = 1.0;
};

// A photon leaving the light `source` (lights first, then the environment) towards the media's
// bounding sphere (centre c, radius r); power per photon for n photons of that source.
// strat: if given, the 2-D sample that places the photon (the disc point, or a point light's direction).
// Always consumes 4 uniform numbers.
Photon emit(const SceneContext& ctx, size_t source, const Vec3& c, double r, double n, Rng& rng,
            const double* strat = nullptr);

// The lines of a light's photons that can meet the media. For a directional light (along w): the cells of a
// raster over the square about emit's disc (normal to w, centre c, radius r) onto which some cell of non-zero
// majorant projects along w (the projection of its box, widened to a rectangle of the raster's axes). For a
// point light outside the media's sphere: the cells of a raster over the plane through c normal to the axis a
// from the light to c, within the cone towards the sphere, onto which such a cell projects from the light (the
// rectangle about its 8 corners' projections). A photon of emit's on any other line flies past every medium;
// for a sphere the disc (of the sphere about its bounding box) is three times its cross-section, and on the
// suite's spheres and the Disney cloud 2/3 to 3/4 of emit's photons met nothing. emit_over draws over the
// footprint only.
struct LightFootprint {
  Frame frame{Vec3(0, 0, 1)};  // about w (directional) or a (point), as emit's disc or cone
  Vec3 origin{0.0};  // directional: the disc's centre c - 2 r w, where emit's photons start; point: c
  bool from_point = false;
  Vec3 light{0.0};              // a point light's position
  double dist = 0.0;            // from a point light to c
  double half = 0.0;            // the raster's half side (r; a point light's cone's radius on the plane)
  double cell = 0.0;            // the raster's cell side
  int res = 0;                  // cells per side (the square [-half, half]^2 of the frame's s, t)
  std::vector<uint32_t> cells;  // the footprint's cells, v res + u
  // The share of emit's photons (through the disc; into the cone) whose lines the footprint holds, in
  // expectation: its area over the disc's; a point light's solid angle over the cone's.
  double share = 1.0;
  double area() const { return double(cells.size()) * cell * cell; }
};
// The footprint of a directional light's beam along w, or of a point light at `light` (with `point`) outside
// the sphere (c, r), on the majorant grid's non-empty cells (raster cells of half the grid's smallest cell
// side, 8 to 512 per side); none where it covers 90 % of emit's photons or more, or the light is inside the
// sphere.
std::optional<LightFootprint> light_footprint(const MajorantGrid& majorants, const Vec3& w, const Vec3& c,
                                              double r);
std::optional<LightFootprint> point_light_footprint(const MajorantGrid& majorants, const Vec3& light,
                                                    const Vec3& c, double r);
// A photon of the footprint's light (irradiance E of a directional light, intensity I of a point light), for n
// photons: uniform over the footprint's cells, with power E area / n; a point light's towards a uniform point q of
// them, with power I area dist / (|q - light|^3 n) (the solid angle's density over the plane's). Consumes 4
// uniform numbers, as emit.
Photon emit_over(const LightFootprint& fp, const Rgb& power, double n, Rng& rng);

// emit for a scene with surfaces: the light's photons also reach the media by way of the surfaces (the
// sunlit ground under a cloud lights its base; emit's photons, all aimed at the media's sphere, land only
// in the media's own shadow). With probability kAimedShare a photon is emit's; otherwise a directional
// light's or the environment's photon crosses the plane through c normal to its direction at distance rho
// from c with density h / (2 pi (h^2 + rho^2)^(3/2)) over the whole plane, h the distance from c along
// the photon's direction to the first surface (at least r): the light a diffuse ground h away sends into
// the media falls off so (their solid angle times the cosine at the ground), so the photons' weights times
// what they bring stay bounded. A point light's photon goes in a uniform direction, a spot's into a
// uniform direction of its cone. The power is over the mixture's density (as a starting weight over
// emit's power), and every photon starts `back` behind the plane along its line (photon_start_distance:
// behind the surfaces' and the media's bounds). Area
// lights (whose photons already leave in every direction) and spots whose cone is the narrower are emit's.
// Consumes 5 uniform numbers (then emit's 4 where it falls back to emit).
inline constexpr double kAimedShare = 0.75;
// What emit_with_surfaces needs of the scene once per grid, not per photon: how far behind the plane
// through c its photons start (photon_start_distance), and per light the plane's h for a directional light
// (the same for all its photons; 0 for the others). emit_with_surfaces takes the one made for its c and r.
struct SurfaceEmission {
  double back = 0.0;
  std::vector<double> plane_h;
};
SurfaceEmission surface_emission(const SceneContext& ctx, const Vec3& c, double r);
Photon emit_with_surfaces(const SceneContext& ctx, size_t source, const Vec3& c, double r,
                          const SurfaceEmission& se, double n, Rng& rng);
// How far behind the plane through c emit_with_surfaces' photons start: emit's 2 r past the farthest
// corner of the surfaces' bounds.
double photon_start_distance(const SceneContext& ctx, const Vec3& c, double r);
// The far plane's h for photons along w: the distance from c along w to the first surface, at least r.
double plane_height(const SceneContext& ctx, const Vec3& c, const Vec3& w, double r);
// True when every medium's sigma_s and sigma_a are equal in all channels (one photon pass carries RGB).
bool grey_media(const SceneContext& ctx);

// A batch's share of the tallies: `size` floats, zero at the start.
struct TallyView {
  float* values = nullptr;
  size_t count = 0;
  float* data() const { return values; }
  size_t size() const { return count; }
  float& operator[](size_t i) const { return values[i]; }
};

// What one batch of photons has written and spent.
struct PhotonBatch {
  TallyView tally;                  // the grid's per-node sums, laid out as the grid wants (zero at start)
  double collisions = 0.0;          // real collisions so far (the work budget's measure)
  double null_collisions = 0.0;     // tentative collisions that were not real (the scatter grid counts them)
  uint64_t rejection_failures = 0;  // scatters whose direction sample_by_rejection could not draw
};

// Traces photons j = 0 .. total - 1, each with its own stream Rng(stream_seed, j), by
// trace_photon(j, rng, batch), in kPhotonBatches fixed batches run in parallel. A batch stops starting
// photons once its collisions exceed kEventsPerPhoton per planned photon and scales its tally by
// planned / traced photons. Returns the batches' tallies summed in order, times `scale`, and adds
// their rejection failures to *rejection_failures.
using TracePhoton = std::function<void(size_t j, Rng& rng, PhotonBatch& batch)>;
FloatArray trace_photons(size_t total, uint64_t stream_seed, size_t tally_size, double scale,
                         const TracePhoton& trace_photon, uint64_t* rejection_failures);

// A batch tally laid out otherwise than the result: trace_photons_folded's tally has tally_size floats
// per batch, and fold(tally, node, weight, acc) adds weight times node `node`'s result (out_floats
// values) to acc. (The scatter grid keeps one single-colour block per light of grey media, 9 floats per
// node instead of 27: a third of the cache lines per splat; issue 12.)
struct TallyFold {
  size_t nodes = 0;
  int out_floats = 0;
  std::function<void(const float* tally, size_t node, double weight, double* acc)> fold;
  // Result floats (indices < out_floats) whose share from each batch is also kept (per_batch below).
  std::vector<int> probes;
};
// trace_photons with the batches' tallies folded (in order, in double) into nodes x out_floats values.
// per_batch (if not null): per node, per batch, per probe, that batch's share of the probe's value (times
// `scale`, as the result): the batches are independent, so their spread is the result's noise.
FloatArray trace_photons_folded(size_t total, uint64_t stream_seed, size_t tally_size, double scale,
                                const TallyFold& fold, const TracePhoton& trace_photon,
                                uint64_t* rejection_failures, FloatArray* per_batch = nullptr);

// The share of the majorant that bounds an extinction which keeps, of each medium i, its absorption
// and kept(i) (in [0, 1]) of its scattering (the colour grid's tint, at most 1, only lowers it):
// max over media of max_c (sigma_a + kept sigma_s) / max_c (sigma_a + sigma_s). 1 without media.
double majorant_share(const SceneMedia& media, const std::function<double(int)>& kept);

// Flies a photon from x along w: delta tracking against `majorants` (the scene's, or the photons'
// own tighter grid) with real collisions at density sigma(p) (<= the majorant times majorant_scale); on_flight(x, w, t_end) for each flight (t_end infinite when the photon leaves the media;
// a flight that meets a surface ends there and on_surface(hit, &w) -> bool decides: false absorbs the
// photon, true sends it on along the new w from the surface),
// then on_collision(xc, &w) -> bool at each real collision xc (false ends the photon; it may turn w).
// At most kMaxPhotonEvents collisions; each one that does not end the photon adds 1 to *collisions.
// sigma may instead decide each tentative collision itself: sigma(p, maj) -> bool, true for a real
// collision (the scatter grid's chromatic photons, which weight null collisions per channel).
template <typename Sigma, typename OnFlight, typename OnCollision, typename OnSurface>
void walk_photon(const SceneContext& ctx, const MajorantGrid& majorants, Vec3 x, Vec3 w,
                 double majorant_scale, Rng& rng, double* collisions, Sigma&& sigma, OnFlight&& on_flight,
                 OnCollision&& on_collision, OnSurface&& on_surface) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  // Constant-density shapes: over their pieces (one exponential step per collision, as `pathtrace`
  // does), not cell by cell of the scene's majorant grid (one per cell crossed).
  const bool pieces = ctx.analytic.active() && &majorants == &ctx.majorants;
  for (int events = 0; events < kMaxPhotonEvents; ++events, *collisions += 1.0) {
    bool hit = false;
    Vec3 xc;
    SurfaceHit surface;
    const bool to_surface = ctx.surfaces.intersect(x, w, kInf, &surface);
    const auto visit = [&](auto&& segment) {
      if (pieces)
        ctx.analytic.traverse(x, w, surface.t, segment);
      else
        majorants.traverse(x, w, 0.0, surface.t, segment);
    };
    const bool reached = track_segments(visit, x, w, majorant_scale, rng, [&](const Vec3& p, double maj) {
      bool real;
      if constexpr (std::is_invocable_r_v<bool, Sigma, const Vec3&, double>) {
        real = sigma(p, maj);
      } else {
        const double s = sigma(p);
        NIMBUS_DCHECK(s >= 0.0 && s <= maj);  // a real collision's probability s / maj in [0, 1]
        real = rng.uniform() * maj < s;
      }
      if (real) {
        hit = true;
        xc = p;
        return false;
      }
      return true;
    });
    if (reached && to_surface) {
      on_flight(x, w, surface.t);
      if (!on_surface(surface, &w)) return;
      x = SceneSurfaces::offset(surface, w);
      continue;
    }
    on_flight(x, w, hit ? (xc - x).length() : kInf);
    if (!hit || !on_collision(xc, &w)) return;
    NIMBUS_DCHECK(std::abs(w.length() - 1.0) < 1e-6);
    x = xc;
  }
}

// The media's shares of the scattering at a collision: part[i] = share(i) sigma_s_i[c].
struct ScatteringShares {
  double part[kMaxMedia];
  double sum = 0.0;
  int count = 0;  // mp.count
};
template <typename Share>
ScatteringShares scattering_shares(const MediumPoint& mp, int media_count, int c, Share&& share) {
  NIMBUS_DCHECK(mp.count <= media_count);
  ScatteringShares s;
  s.count = mp.count;
  for (int i = 0; i < mp.count && i < media_count; ++i) {
    s.part[i] = share(i) * mp.sigma_s_i[i][c];
    NIMBUS_DCHECK(s.part[i] >= 0.0);
    s.sum += s.part[i];
  }
  return s;
}

// Medium m with probability part[m] / sum (one uniform number); sum > 0.
inline int choose_medium(const ScatteringShares& s, Rng& rng) {
  NIMBUS_DCHECK(s.sum > 0.0);
  double u = rng.uniform() * s.sum;
  int m = 0;
  while (m + 1 < s.count && u >= s.part[m]) u -= s.part[m++];
  return m;
}

// A direction by rejection: candidates from draw() until accept(candidate) (which draws its own
// uniform number), at most kMaxRejectionTries; the accepted one is written to *w. Expected tries are
// 1 / (accepted share), at most 100 for the shares `mfs` allows (peak_fraction <= 0.99). When every try
// fails, *w is left as it was — the photon flies on undeflected, as if it had not scattered — and the
// result is false, so the caller can count it (PhotonBatch::rejection_failures).
template <typename Draw, typename Accept>
bool sample_by_rejection(Vec3* w, Draw&& draw, Accept&& accept) {
  for (int tries = 0; tries < kMaxRejectionTries; ++tries) {
    const Vec3 candidate = draw();
    if (accept(candidate)) {
      *w = candidate;
      return true;
    }
  }
  return false;
}

}  // namespace nimbus
