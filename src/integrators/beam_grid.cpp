// The beam grid (integrators/beam_grid.h): its photons (through the shared photon tracer) and its
// lookup.
#include "integrators/beam_grid.h"

#include <cmath>
#include <limits>

#include "core/check.h"
#include "integrators/photon_tracer.h"

namespace nimbus {
namespace {

// Per node: traced (rgb), traced x mean cosine (rgb), straight (rgb), and with a camera (peak_toward)
// traced x P_peak towards the camera (rgb).
constexpr int kBaseFloats = 9, kCameraFloats = 12;
constexpr double kR2a1 = 0.75487766624669276, kR2a2 = 0.56984029099805327;  // the R2 sequence
constexpr double kRoulette = 0.05;
// Deposit samples (and the loss's midpoint rule) at most this many node spacings apart: 0.5 (0.25
// before) halves the deposits and density lookups with no change in the validation errors beyond their
// seed-to-seed spread (docs/benchmarks.md, issue 12).
constexpr double kDepositStep = 0.5;  // roulette below this ratio of weight to T_wide

// Adds v (channel ch) with trilinear weights st to the tally: to the straight column, or to the traced
// one and (times mu) the traced x cosine one.
// stride: floats per node; pk: P_peak towards the camera (stride kCameraFloats only).
void splat(float* tally, int stride, const TrilinearStencil& st, int ch, double v, double mu, double pk,
           bool straight) {
  for (int j = 0; j < 8; ++j)
    if (st.weight[j] > 0.0) {
      float* node = &tally[st.node[j] * stride];
      if (straight) {
        node[6 + ch] += float(st.weight[j] * v);
      } else {
        node[ch] += float(st.weight[j] * v);
        node[3 + ch] += float(st.weight[j] * v * mu);
        if (stride == kCameraFloats) node[9 + ch] += float(st.weight[j] * v * pk);
      }
    }
}

// One photon's state: the channel whose coefficients drive it, its weight and its weight at emission.
struct BeamWalk {
  int c;
  Rgb weight;
  double w0;
  MediumPoint mp;
};

// The photons of one light of a beam grid: where photon j enters, what its flights deposit and what its
// peak scatters do.
struct BeamPhotons {
  const SceneContext& ctx;
  const std::vector<const PhaseSplit*>& splits;
  const std::vector<double>& peak_fraction;
  const TransmittanceGrid& T_wide;  // the light's reduced shadow map
  const NodeGrid& grid;
  size_t light;
  const PointLight* point;  // or null: a directional light
  Rgb strength;             // phi_0 = strength (/ r^2)
  Vec3 dir_w;               // a directional light's direction of travel
  bool grey;                // one pass carrying RGB (else one pass per channel)
  size_t per_light;
  Vec3 centre;  // of the node grid's bounding sphere, which the photons are aimed at
  double radius;
  double majorant_scale;          // the share of the majorant that bounds the peak-scatter rate
  const Vec3* camera;             // tally P_peak (of medium 0) towards this point, or null
  int stride;                     // floats per node
  const MajorantGrid* majorants;  // the photons' tracking majorants (null: the scene's)

  void trace(size_t j, Rng& rng, PhotonBatch& batch) const;
  Rgb deposit(float* tally, const Vec3& x, const Vec3& w, double t_end, Rgb weight, int c,
              bool straight) const;
  bool scatter(const Vec3& xc, Vec3* w, BeamWalk& walk, Rng& rng, PhotonBatch& batch) const;
};

// Track-length deposit of the flight x + t w, t in [0, t_end] (clipped to the grid), starting with
// `weight` (channel c only unless grey) and losing exp(-int sigma_loss) along the way (midpoint
// rule at the deposit samples); each sample divided by the straight-line model at that point.
// Returns the weight at t_end.
Rgb BeamPhotons::deposit(float* tally, const Vec3& x, const Vec3& w, double t_end, Rgb weight, int c,
                         bool straight) const {
  double t0, t1;
  if (!grid.bounds.intersect(x, w, 0.0, t_end, &t0, &t1) || !(t1 - t0 > 0.0)) return weight;
  const double len = t1 - t0;
  const int n = std::max(1, int(std::ceil(len / (kDepositStep * grid.min_spacing()))));
  const double dl = len / n;
  for (int k = 0; k < n; ++k) {
    const Vec3 q = x + w * (t0 + (k + 0.5) * dl);
    const Rgb loss = reduced_sigma_t(ctx.media, q, peak_fraction);
    const Rgb mid = weight * exp(-loss * (0.5 * dl));
    weight = mid * exp(-loss * (0.5 * dl));
    const Rgb tw = T_wide.lookup(q);
    const double geo = point ? 1.0 / std::max(1e-300, dot(q - point->position, q - point->position)) : 1.0;
    // The cosine between the travel direction and the straight one from the light.
    const double mu = straight ? 1.0 : point ? dot(w, normalize(q - point->position)) : dot(w, dir_w);
    // The peak-only light's last peak scatter towards the camera (the forward-peak term's angular factor).
    const double pk = camera && !straight ? splits[0]->peak(dot(w, normalize(*camera - q))) : 0.0;
    const TrilinearStencil st = grid.stencil(q);
    for (int ch = 0; ch < 3; ++ch) {
      if ((!grey && ch != c) || !(tw[ch] > 1e-30)) continue;
      const double v = mid[ch] * dl / (tw[ch] * geo);
      NIMBUS_DCHECK(v >= 0.0 && std::isfinite(v));
      splat(tally, stride, st, ch, v, mu, pk, straight);
    }
  }
  return weight;
}

void BeamPhotons::trace(size_t j, Rng& rng, PhotonBatch& batch) const {
  BeamWalk walk;
  walk.c = int(j / per_light);
  const size_t k = j % per_light;
  double strat[2] = {0.5 + k * kR2a1, 0.5 + k * kR2a2};
  for (double& u : strat) u -= std::floor(u);
  const Photon ph = emit(ctx, light, centre, radius, double(per_light), rng, strat);
  // Power per photon over phi_0's strength: the geometry of the emission only.
  walk.weight = Rgb(0.0);
  for (int ch = 0; ch < 3; ++ch)
    if ((grey || ch == walk.c) && strength[ch] > 0.0) walk.weight[ch] = ph.power[ch] / strength[ch];
  if (max_component(walk.weight) <= 0.0) return;
  walk.w0 = walk.weight[walk.c];
  // The same photon undeflected: the straight-line model with the same emission (a control
  // variate: R = traced / straight cancels the emission's sampling noise).
  deposit(batch.tally.data(), ph.x, ph.w, std::numeric_limits<double>::infinity(), walk.weight, walk.c, true);
  // Flights end at peak scatters only (rate sum_m f_m sigma_s,m); absorption and wide scatters are the
  // continuous loss exp(-int sigma_loss) on the weight (zero variance in a uniform medium).
  const auto peak_share = [&](int i) { return peak_fraction[i]; };
  walk_photon(
      ctx, majorants ? *majorants : ctx.majorants, ph.x, ph.w, majorant_scale, rng, &batch.collisions,
      [&](const Vec3& p) {
        ctx.media.eval(p, &walk.mp);
        return scattering_shares(walk.mp, ctx.media.count(), walk.c, peak_share).sum;
      },
      [&](const Vec3& x, const Vec3& w, double t_end) {
        walk.weight = deposit(batch.tally.data(), x, w, t_end, walk.weight, walk.c, false);
      },
      [&](const Vec3& xc, Vec3* w) { return scatter(xc, w, walk, rng, batch); },
      // A reflection is a wide scatter: not part of the forward-peaked beam.
      [](const SurfaceHit&, Vec3*) { return false; });
}

// A peak scatter at xc: roulette, medium, direction (from P_peak). False ends the photon.
bool BeamPhotons::scatter(const Vec3& xc, Vec3* w, BeamWalk& walk, Rng& rng, PhotonBatch& batch) const {
  const int c = walk.c;
  // Roulette on the ratio to the model (what is deposited), not on the weight alone.
  const double tw = T_wide.lookup(xc)[c] * walk.w0;
  if (tw > 0.0 && walk.weight[c] < kRoulette * tw) {
    const double keep = walk.weight[c] / (kRoulette * tw);
    NIMBUS_DCHECK(keep >= 0.0 && keep < 1.0);
    if (rng.uniform() >= keep) return false;
    walk.weight *= 1.0 / keep;
  }
  ctx.media.eval(xc, &walk.mp);
  const ScatteringShares shares =
      scattering_shares(walk.mp, ctx.media.count(), c, [&](int i) { return peak_fraction[i]; });
  if (!(shares.sum > 0.0)) return false;
  const int m = choose_medium(shares, rng);
  const Phase& phase = ctx.media.phase(m);
  const double f = peak_fraction[m];
  // P_peak by rejection from P: accept with f P_peak / P (expected 1 / f tries).
  const bool drawn = sample_by_rejection(
      w,
      [&] {
        // u2 first: the order GCC gave phase_sample(phase, w, rng.uniform(), rng.uniform()) before.
        const double u2 = rng.uniform(), u1 = rng.uniform();
        return phase_sample(phase, *w, u1, u2);
      },
      [&](const Vec3& candidate) {
        const double mu = dot(candidate, *w), p_full = phase_eval(phase, mu);
        return p_full > 0.0 && rng.uniform() * p_full < f * splits[m]->peak(mu);
      });
  if (!drawn) ++batch.rejection_failures;  // the photon flies on undeflected (see sample_by_rejection)
  return true;
}

}  // namespace

BeamGrid::BeamGrid(const SceneContext& ctx, const std::vector<const PhaseSplit*>& splits,
                   const std::vector<double>& peak_fraction,
                   const std::vector<TransmittanceGrid>& reduced_maps, int photons, int resolution,
                   uint64_t seed, const Vec3* camera, const MajorantGrid* majorants)
    : stride_(camera ? kCameraFloats : kBaseFloats) {
  if (camera) camera_ = *camera;
  values_.resize(ctx.lights.size());
  const Bounds media_bounds = ctx.media.bounds();
  if (media_bounds.empty() || photons <= 0 || reduced_maps.size() != ctx.lights.size()) return;
  grid_ = node_grid_padded(media_bounds, resolution);
  const bool grey = grey_media(ctx);
  const size_t per_light = size_t(photons);
  const size_t total = size_t(grey ? 1 : 3) * per_light;
  const Vec3 centre = (media_bounds.lo + media_bounds.hi) * 0.5;
  // Photons cover the whole node grid (its padding included), so every node's estimate is complete.
  const double radius = 0.5 * (grid_.bounds.hi - grid_.bounds.lo).length() * (1.0 + 1e-9) + 1e-12;

  const double scale = majorant_share(ctx.media, [&](int i) { return peak_fraction[i]; });
  for (size_t l = 0; l < ctx.lights.size(); ++l) {
    const Light& light = ctx.lights[l];
    const auto* dir = std::get_if<DirectionalLight>(&light);
    const auto* point = std::get_if<PointLight>(&light);
    if (!dir && !point) continue;
    const BeamPhotons beam{.ctx = ctx,
                           .splits = splits,
                           .peak_fraction = peak_fraction,
                           .T_wide = reduced_maps[l],
                           .grid = grid_,
                           .light = l,
                           .point = point,
                           .strength = dir ? dir->irradiance : point->intensity,
                           .dir_w = dir ? normalize(dir->direction) : Vec3(0.0),
                           .grey = grey,
                           .per_light = per_light,
                           .centre = centre,
                           .radius = radius,
                           .majorant_scale = scale,
                           .camera = camera ? &camera_ : nullptr,
                           .stride = stride_,
                           .majorants = majorants};
    // The batches' sums divided by the node volume.
    values_[l] = trace_photons(
        total, seed ^ 0x7065616b6265616dull ^ (uint64_t(l) << 40), grid_.size() * size_t(stride_),
        1.0 / grid_.cell_volume(), [&](size_t j, Rng& rng, PhotonBatch& batch) { beam.trace(j, rng, batch); },
        &rejection_failures_);
  }
}

bool BeamGrid::lookup(size_t light, const Vec3& p, Rgb* factor, Rgb* mean_cosine, Rgb* peak_toward) const {
  if (light >= values_.size() || values_[light].empty() || !grid_.bounds.contains(p)) return false;
  const std::vector<float>& v = values_[light];
  const TrilinearStencil st = grid_.stencil(p);
  Rgb r(0.0), m(0.0), straight(0.0), pk(0.0);
  for (int k = 0; k < 8; ++k)
    for (int c = 0; c < 3; ++c) {
      const float* node = &v[st.node[k] * size_t(stride_)];
      r[c] += st.weight[k] * node[c];
      m[c] += st.weight[k] * node[3 + c];
      straight[c] += st.weight[k] * node[6 + c];
      if (stride_ == kCameraFloats) pk[c] += st.weight[k] * node[9 + c];
    }
  for (int c = 0; c < 3; ++c) {
    (*factor)[c] = straight[c] > 0.0 ? r[c] / straight[c] : 1.0;
    (*mean_cosine)[c] = r[c] > 0.0 ? std::clamp(m[c] / r[c], -1.0, 1.0) : 1.0;
    if (peak_toward) (*peak_toward)[c] = r[c] > 0.0 ? pk[c] / r[c] : 0.0;
  }
  return true;
}

size_t BeamGrid::memory_bytes() const {
  size_t bytes = 0;
  for (const auto& v : values_) bytes += v.size() * sizeof(float);
  return bytes;
}

}  // namespace nimbus
