// The scatter grid (integrators/scatter_grid.h): its photons (through the shared photon tracer), its
// pre-filtered levels and its lookups.
// long-file: the photons' two walks (one pass per channel, or hero channels for chromatic media) share
// the deposit and tally code of this file's anonymous namespace; a second file would have to expose it.
#include "integrators/scatter_grid.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <optional>

#include "core/check.h"
#include "core/sh.h"
#include "integrators/beam_grid.h"
#include "integrators/grid_denoise.h"
#include "integrators/photon_tracer.h"
#include "integrators/shadow_map.h"
#include "media/emission_sampler.h"

namespace nimbus {
namespace {

constexpr int kMaxWideScatters = 1024;  // photons are ended after this many wide scatters (or
                                        // kMaxPhotonEvents real collisions)

// Adds the per-node values `add` (count floats, node offset `first`) times the trilinear weights at q
// to the tally's nodes around q (only to the live ones, where `live` is given; see live_nodes). One
// flight's values are the same at every sample: they are computed once, in float, and the node loop is
// a contiguous multiply-add the compiler vectorises.
void splat(float* tally, const NodeGrid& grid, const uint8_t* live, int floats_per_node, int first, int count,
           const Vec3& q, const float* add) {
  const TrilinearStencil st = grid.stencil(q);
  for (int k = 0; k < 8; ++k) {
    const float wt = float(st.weight[k]);
    if (wt <= 0.0f || (live && !live[st.node[k]])) continue;
    float* node = &tally[st.node[k] * floats_per_node + first];
    for (int i = 0; i < count; ++i) node[i] += wt * add[i];
  }
}

// The same sample whole to one of the 8 nodes, drawn by uniforms u with probability equal to its
// trilinear weight (Splat::stochastic, Splat::stratified): the expected tally is splat's, one node
// written instead of 8.
void splat_one(float* tally, const NodeGrid& grid, const uint8_t* live, int floats_per_node, int first,
               int count, const Vec3& q, const double u[3], const float* add) {
  const size_t n = grid.random_node(q, u);
  if (live && !live[n]) return;
  float* node = &tally[n * floats_per_node + first];
  for (int i = 0; i < count; ++i) node[i] += add[i];
}

// A flight's deposit samples, k = 0 .. n - 1 at x + w (t0 + (k + offset) len / n), offset in [0, 1),
// through `splat` or (with corner uniforms) `splat_one`.
void splat_flight(float* tally, const NodeGrid& grid, const uint8_t* live, int floats_per_node, int first,
                  int count, const Vec3& x, const Vec3& w, double t0, double len, int n, double offset,
                  const float* add, CornerUniforms* corners) {
  if (!corners) {
    for (int k = 0; k < n; ++k)
      splat(tally, grid, live, floats_per_node, first, count, x + w * (t0 + (k + offset) * len / n), add);
    return;
  }
  corners->start_flight();
  for (int k = 0; k < n; ++k) {
    double u[3];
    corners->next(k, u);
    splat_one(tally, grid, live, floats_per_node, first, count, x + w * (t0 + (k + offset) * len / n), u,
              add);
  }
}

// Where a photon's flights go in its batch's tally: the RGB block (per node: channel c at [coeffs c + h],
// as ScatterGrid::values_), or, for a source whose photons all carry one colour (grey media, a light
// or a constant environment), that source's single-colour block (per node: coeffs floats, the power
// in units of `colour`, which ScatterGrid::trace's fold multiplies back in). The single-colour block
// is a third of the RGB block's floats and cache lines per splat (docs/benchmarks.md, issue 12).
struct TallyBlock {
  float* mono = nullptr;  // the source's single-colour block, or null: the RGB block
  Rgb colour{1.0};        // the source's colour (max channel 1)
  int channel = 0;        // its largest channel
};

// Track-length deposit of the flight x + t w, t in [0, t_end] (clipped to the node grid): samples at
// most `step` node spacings apart, at `offset` within each equal part of the clipped flight
// (ScatterGridSettings::deposit_step), each splatting its share of power x length times the harmonics of w
// (into block.mono when given; else into the RGB block `tally`, where only the channels from the first
// to the last with non-zero power are touched); trilinearly, or with `corners` to one node per sample.
void deposit_flight(float* tally, const TallyBlock& block, const NodeGrid& grid, const uint8_t* live,
                    int bands, const Vec3& x, const Vec3& w, double t_end, const Rgb& power, double step,
                    double offset, CornerUniforms* corners) {
  double t0, t1;
  if (!grid.bounds.intersect(x, w, 0.0, t_end, &t0, &t1)) return;
  const double len = t1 - t0;
  if (!(len > 0.0)) return;
  const int n = std::max(1, int(std::ceil(len / (step * grid.min_spacing()))));
  const Rgb v = power * (len / n);
  NIMBUS_DCHECK(min_component(v) >= 0.0 && std::isfinite(max_component(v)));
  const int coeffs = bands * bands;
  double y[kShMaxBands * kShMaxBands];
  if (block.mono) {
    const double a = v[block.channel];  // v = a colour (the source's photons carry its colour)
    NIMBUS_DCHECK(std::abs(v.x - a * block.colour.x) <= 1e-9 * a &&
                  std::abs(v.y - a * block.colour.y) <= 1e-9 * a &&
                  std::abs(v.z - a * block.colour.z) <= 1e-9 * a);
    if (!(a > 0.0)) return;
    sh_eval(w, bands, y);
    float add[kShMaxBands * kShMaxBands];
    for (int h = 0; h < coeffs; ++h) add[h] = float(a * y[h]);
    splat_flight(block.mono, grid, live, coeffs, 0, coeffs, x, w, t0, len, n, offset, add, corners);
    return;
  }
  int c_lo = 0, c_hi = 2;
  while (c_lo < 3 && v[c_lo] == 0.0) ++c_lo;
  while (c_hi >= c_lo && v[c_hi] == 0.0) --c_hi;
  if (c_lo > c_hi) return;
  sh_eval(w, bands, y);
  float add[3 * kShMaxBands * kShMaxBands];
  for (int c = c_lo; c <= c_hi; ++c)
    for (int h = 0; h < coeffs; ++h) add[coeffs * (c - c_lo) + h] = float(v[c] * y[h]);
  const int first = coeffs * c_lo, count = coeffs * (c_hi - c_lo + 1);
  splat_flight(tally, grid, live, 3 * coeffs, first, count, x, w, t0, len, n, offset, add, corners);
}

// The next pre-filtered level: the values (`floats` per node) of `fine` at its nodes 2j, filtered with
// the tent (1/4, 1/2, 1/4) per axis, on `coarse` (nodes beyond fine's last are clamped to it).
FloatArray tent_downsample(const NodeGrid& fine, const float* src, const NodeGrid& coarse, int floats) {
  FloatArray values(coarse.size() * floats, 0.0f);
  const std::array<int, 3> nb = fine.nodes;
  auto at = [&](int x, int y, int z) {
    x = std::clamp(x, 0, nb[0] - 1), y = std::clamp(y, 0, nb[1] - 1), z = std::clamp(z, 0, nb[2] - 1);
    return src + fine.index(x, y, z) * floats;
  };
  tbb::parallel_for(0, coarse.nodes[2], [&](int z) {
    for (int y = 0; y < coarse.nodes[1]; ++y)
      for (int x = 0; x < coarse.nodes[0]; ++x) {
        float* out = &values[coarse.index(x, y, z) * floats];
        for (int dz = -1; dz <= 1; ++dz)
          for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
              const double w = (dx ? 0.25 : 0.5) * (dy ? 0.25 : 0.5) * (dz ? 0.25 : 0.5);
              const float* in = at(2 * x + dx, 2 * y + dy, 2 * z + dz);
              for (int k = 0; k < floats; ++k) out[k] += float(w * in[k]);
            }
      }
  });
  return values;
}

// A photon emitted by the media: a point drawn by the emission sampler, an isotropic direction, power
// 4 pi j(x) / (pdf(x) n) (emitted power per unit volume 4 pi j; an unbiased estimate of the whole).
Photon emit_from_media(const EmissionSampler& sampler, const SceneMedia& media, double n, Rng& rng) {
  const double u0 = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform(), u3 = rng.uniform();
  const double v1 = rng.uniform(), v2 = rng.uniform();
  double pdf = 0.0;
  Photon p;
  p.x = sampler.sample(u0, u1, u2, u3, &pdf);
  p.w = spherical_direction(1.0 - 2.0 * v1, 2.0 * kPi * v2, Vec3(0, 0, 1));
  p.power = pdf > 0.0 ? media.emission(p.x) * (4.0 * kPi / (pdf * n)) : Rgb(0.0);
  return p;
}

// Per source: the offset in floats of its single-colour block in a batch's tally (-1: none, the RGB
// block), its colour (max channel 1) and largest channel.
struct SourceBlock {
  int64_t offset = -1;
  Rgb colour{1.0};
  int channel = 0;
};

// Sources whose photons all carry one colour (grey media: a directional, point or spot light, or a
// constant environment) deposit into a single-colour block of their own (TallyBlock); the others (an
// environment image, the media's emission, area lights, or any source of coloured media) into the RGB
// block (first in the tally), which is left out when no source needs it. Sources are numbered as
// ScatterPhotons::trace numbers them (lights, then the environment, then the emission). Returns the
// floats of a batch's tally; *rgb_size: those of the RGB block.
size_t assign_blocks(const SceneContext& ctx, bool grey, size_t lights, size_t sources, size_t nodes,
                     int coeffs, std::vector<SourceBlock>* blocks, size_t* rgb_size) {
  blocks->assign(sources, SourceBlock{});
  size_t mono = 0;
  for (size_t src = 0; src < sources && grey; ++src) {
    std::optional<Rgb> colour;
    if (src < lights) {
      const Light& light = ctx.lights[src];
      if (const auto* d = std::get_if<DirectionalLight>(&light)) colour = d->irradiance;
      if (const auto* p = std::get_if<PointLight>(&light)) colour = p->intensity;
      if (const auto* p = std::get_if<SpotLight>(&light)) colour = p->intensity;
    } else if (src == lights && ctx.has_environment && !ctx.env_map) {
      colour = ctx.environment;
    }
    if (!colour || !(max_component(*colour) > 0.0) || !(min_component(*colour) >= 0.0)) continue;
    SourceBlock& b = (*blocks)[src];
    b.channel = colour->x >= colour->y ? (colour->x >= colour->z ? 0 : 2) : (colour->y >= colour->z ? 1 : 2);
    b.colour = *colour / (*colour)[b.channel];
    b.offset = int64_t(mono++);  // in blocks for now
  }
  *rgb_size = mono < sources ? nodes * 3 * coeffs : 0;
  for (SourceBlock& b : *blocks)
    if (b.offset >= 0) b.offset = int64_t(*rgb_size + size_t(b.offset) * nodes * coeffs);
  return *rgb_size + mono * nodes * coeffs;
}

// Adds wt times node n of a batch's tally (laid out by assign_blocks) to acc (as ScatterGrid::values_
// lays out a node: channel c at [coeffs c + h]): the RGB block, then each single-colour block times
// its colour.
void fold_node(const std::vector<SourceBlock>& blocks, size_t rgb_size, int coeffs, const float* tally,
               size_t n, double wt, double* acc) {
  const int rgb_floats = 3 * coeffs;
  if (rgb_size > 0)
    for (int i = 0; i < rgb_floats; ++i) acc[i] += wt * tally[n * rgb_floats + i];
  for (const SourceBlock& b : blocks) {
    if (b.offset < 0) continue;
    const float* t = tally + b.offset + n * coeffs;
    for (int c = 0; c < 3; ++c)
      for (int h = 0; h < coeffs; ++h) acc[c * coeffs + h] += wt * b.colour[c] * t[h];
  }
}

// The colour (max channel 1) every source's photons carry, where every source has a single-colour
// block and all have the same colour; none otherwise.
std::optional<Rgb> common_colour(const std::vector<SourceBlock>& blocks, size_t rgb_size) {
  if (rgb_size > 0 || blocks.empty()) return std::nullopt;
  for (const SourceBlock& b : blocks)
    if (b.offset < 0 || !(b.colour == blocks[0].colour)) return std::nullopt;
  return blocks[0].colour;
}

// fold_node for a one-channel grid (common_colour): the single-colour blocks' sum, coeffs per node.
void fold_node_mono(const std::vector<SourceBlock>& blocks, int coeffs, const float* tally, size_t n,
                    double wt, double* acc) {
  for (const SourceBlock& b : blocks) {
    const float* t = tally + b.offset + n * coeffs;
    for (int h = 0; h < coeffs; ++h) acc[h] += wt * t[h];
  }
}

// How the batches' tallies fold into the grid's nodes of `channels` (1: common_colour's) x coeffs floats.
TallyFold tally_fold(const std::vector<SourceBlock>& blocks, size_t rgb_size, int coeffs, size_t nodes,
                     int channels) {
  TallyFold fold;
  fold.nodes = nodes;
  fold.out_floats = channels * coeffs;
  fold.fold = [&blocks, rgb_size, coeffs, channels](const float* tally, size_t n, double wt, double* acc) {
    if (channels == 1)
      fold_node_mono(blocks, coeffs, tally, n, wt, acc);
    else
      fold_node(blocks, rgb_size, coeffs, tally, n, wt, acc);
  };
  return fold;
}

// A photon of chromatic media traced once for all three channels (hero-channel sampling, the balance
// heuristic over channels: Veach's multi-sample MIS with one technique per channel). Photon i of a
// source's n is driven by hero channel c = i mod 3 (a_c = n_c / n of them): delta tracking with real
// collisions at that channel's extinction sigma_c, the medium chosen by its scattering shares. For the
// path x so drawn, f_k(x) is channel k's contribution (per tentative collision: sigma_s,m[k] at a real
// scatter in medium m, maj - sigma_t[k] at a null one) and p_j(x) the density of drawing x with hero
// j; channel k gets
//     W_k = f_k / sum_j a_j p_j,
// which is unbiased for every channel (each channel's paths are drawn by its own hero at least) and
// bounded: W_k <= f_k / (a_k p_k) = (1 / a_k) x the single-channel pass's weight (a product of
// albedos, <= 1). The walk keeps beta_k = f_k / p_c and r_j = p_j / p_c, both divided by max_j r_j after
// each event (no overflow over long walks; W = beta / (a . r) is unchanged by the scale). The roulette
// acts on max_k W_k, which does not depend on the hero, so its survival probability is common to all
// techniques and divides out. Surfaces weight by their albedo per channel.
struct HeroWalk {
  int c;      // the hero channel
  Rgb a;      // a_j: the share of the source's photons with hero j
  Rgb beta;   // f_k / p_c (scaled)
  Rgb r;      // p_j / p_c (scaled by the same factor; max_j r_j = 1)
  Rgb sigma;  // the extinction at the last tentative collision (all channels)
  Rgb weight() const { return beta * (1.0 / (a.x * r.x + a.y * r.y + a.z * r.z)); }
  // An event with channel-k contribution factor f[k] and hero-j density factor p[j] (p[c] > 0).
  void update(const Rgb& f, const Rgb& p) {
    const double pc = p[c];
    NIMBUS_DCHECK(pc > 0.0);
    beta = beta * f * (1.0 / pc);
    r = r * p * (1.0 / pc);
    const double m = max_component(r);
    NIMBUS_DCHECK(m >= r[c] && m > 0.0);
    r = r * (1.0 / m);
    beta = beta * (1.0 / m);
  }
  // Roulette below 0.1 on the largest channel's weight; false ends the photon.
  bool roulette(Rng& rng) {
    const double w = max_component(weight());
    if (w >= 0.1) return true;
    if (rng.uniform() * 0.1 >= w) return false;
    beta = beta * (0.1 / w);
    return true;
  }
};

// The photons of one scatter grid: which source and channel photon j belongs to, what its flights
// deposit and what its real collisions do.
struct ScatterPhotons {
  const SceneContext& ctx;
  const std::vector<const PhaseSplit*>& splits;
  const std::vector<double>& peak_fraction;
  const ScatterGridSettings& s;
  const NodeGrid& grid;
  const uint8_t* live;  // per node: 1 where a lookup in the media can read it (null: every node)
  int bands;
  bool grey;      // one pass carrying RGB power (else one pass per channel, or hero channels)
  bool hero;      // chromatic media in one pass: hero channels with the balance heuristic (HeroWalk)
  size_t lights;  // light sources (then the environment, then the media's emission, if any)
  size_t sources;
  std::vector<size_t> first;        // source i's photons are first[i] .. first[i + 1] - 1 of each pass
  const EmissionSampler* emission;  // null when no medium emits
  Vec3 centre;                      // of the media's bounding sphere, which the photons are aimed at
  double radius;
  SurfaceEmission surface;  // with surfaces: emit_with_surfaces' start and far planes
  int K;                    // flights after wide scatter 1 .. K - 1 are kept
  double majorant_scale;    // the share of the majorant that bounds the extinction the photons see
  // The photons fly over the exact piece of one constant-density shape of grey extinction (walk_photon's
  // `pieces`, the full extinction): its majorant is the extinction wherever a tentative collision falls.
  bool exact_pieces;
  std::vector<SourceBlock> blocks;  // per source, as trace numbers them
  // Per light: a directional or point light's footprint on the media (light_footprint, point_light_footprint;
  // none for other lights, with surfaces, or where it would save little). Its photons are drawn over it, and
  // the light takes the footprint's share of the photons photon_split gives it: the same photons meet the
  // media, in expectation, as from emit's whole disc or cone, without those that would fly past them.
  std::vector<std::optional<LightFootprint>> footprints{};
  size_t planned = 0;  // photon_split's photons per pass, before the footprints' shares
  // Whether flights are deposited: the pilot (pilot_collisions) only counts collisions, so its tally's
  // pages are never touched. The walks draw the same numbers either way.
  bool deposits = true;

  // first = photon_split(..., photons, ...), each footprint's light's count times its share, and surface.
  void split(int photons);
  void trace(size_t j, Rng& rng, PhotonBatch& batch) const;
  // A flight's deposit offset (deposit_flight): a uniform, one per flight, drawn also with
  // deposit_midpoints (which takes 1/2) so that the walks are the same either way.
  double offset(Rng& rng) const {
    const double u = rng.uniform();
    return s.deposit_midpoints ? 0.5 : u;
  }
  // deposit_flight of the flight x + t w, t in [0, t_end], with power, into the batch's tally (block); its
  // offset is drawn whether or not the flight is deposited (deposits), so the walks are the same either way.
  void deposit(PhotonBatch& batch, const TallyBlock& block, const Vec3& x, const Vec3& w, double t_end,
               const Rgb& power, CornerUniforms* corners, Rng& rng) const {
    const double u = offset(rng);
    if (deposits)
      deposit_flight(batch.tally.data(), block, grid, live, bands, x, w, t_end, power, s.deposit_step, u,
                     corners);
  }
  bool reflect(const SurfaceHit& hit, Vec3* w, int c, double* weight, int* order, Rng& rng) const;
  bool bounce(const SurfaceHit& hit, Vec3* w, double* factor, Rng& rng) const;
  // at_xc: the media's values at xc where the walk's tentative collision there already found them (else
  // null: looked up here).
  bool scatter(const Vec3& xc, Vec3* w, int c, double* weight, int* order, Rng& rng, PhotonBatch& batch,
               const MediumPoint* at_xc = nullptr) const;
  // The new direction after a real collision in medium m (weighted and survived); false ends the photon.
  bool turn(int m, Vec3* w, int* order, Rng& rng, PhotonBatch& batch) const;
  // The extinction the photons see at p: the media's own, or reduced by the peaks (similarity transport).
  Rgb extinction(const Vec3& p) const {
    return s.exact_transport ? ctx.media.sigma_t(p) : reduced_sigma_t(ctx.media, p, peak_fraction);
  }
  // The same from the media's values at p (SceneMedia::eval; peak_fraction not empty): the same bits for one
  // untinted medium, equal to rounding otherwise (summed per kind of coefficient rather than per medium).
  Rgb extinction(const MediumPoint& mp) const {
    return s.exact_transport ? mp.sigma_t() : reduced_sigma_t(mp, peak_fraction);
  }
  // Whether a walk's tentative collisions take their extinction from the media's values (eval), which the
  // real collision then reads: not in emitting media, where eval also finds the emission.
  bool values_at_collisions() const {
    return (s.exact_transport || !peak_fraction.empty()) && !ctx.media.emits();
  }
  void trace_hero(const Photon& ph, int hero, const Rgb& share, const TallyBlock& block, int first_order,
                  CornerUniforms* corners, Rng& rng, PhotonBatch& batch) const;
  // A photon of grey media (RGB power) or of channel c's pass (that channel's power only).
  void trace_channel(const Photon& ph, int c, const TallyBlock& block, int first_order,
                     CornerUniforms* corners, Rng& rng, PhotonBatch& batch) const;
  // at_xc: as scatter's.
  bool scatter_hero(const Vec3& xc, Vec3* w, HeroWalk& walk, int* order, Rng& rng, PhotonBatch& batch,
                    const MediumPoint* at_xc = nullptr) const;
};

// The power emit_over takes for a light with a footprint: a directional light's irradiance, a point light's
// intensity.
Rgb footprint_power(const Light& light) {
  if (const auto* d = std::get_if<DirectionalLight>(&light)) return d->irradiance;
  return std::get<PointLight>(light).intensity;
}

void ScatterPhotons::trace(size_t j, Rng& rng, PhotonBatch& batch) const {
  const size_t per_pass = first.back();
  const int pass = int(j / per_pass);
  const size_t k = j % per_pass;
  const size_t src = size_t(std::upper_bound(first.begin(), first.end(), k) - first.begin()) - 1;
  const double n = double(first[src + 1] - first[src]);  // the source's photons per pass
  size_t source = src;
  if (source >= lights) source = ctx.lights.size();  // the environment
  // The constant environment's light is smooth in angle: the grid carries it from its entry (order 0).
  // So is the media's emission (isotropic, the last source): the grid carries it from its first flight.
  // An environment image is not (a sun in it): like a light, mfs takes its first wide scatter on the
  // camera march, and the grid carries its photons after that.
  const bool from_media = emission && src == sources - 1;
  const bool light_like = source < ctx.lights.size() || (source == ctx.lights.size() && ctx.env_map);
  const int first_order = light_like && !from_media ? 1 : 0;
  const int c = pass;  // the channel whose coefficients drive this photon
  const LightFootprint* fp = src < footprints.size() && footprints[src] ? &*footprints[src] : nullptr;
  const Photon ph = from_media             ? emit_from_media(*emission, ctx.media, n, rng)
                    : fp                   ? emit_over(*fp, footprint_power(ctx.lights[src]), n, rng)
                    : ctx.surfaces.empty() ? emit(ctx, source, centre, radius, n, rng)
                                           : emit_with_surfaces(ctx, source, centre, radius, surface, n, rng);
  const SourceBlock& sb = blocks[src];
  const TallyBlock block{.mono = sb.offset >= 0 ? batch.tally.data() + sb.offset : nullptr,
                         .colour = sb.colour,
                         .channel = sb.channel};
  // A stochastic splat's corner choices: from a stream of the photon's own (its walk's stream untouched).
  Rng splat_rng(s.seed ^ 0x73706c6174ull, j);
  CornerUniforms corner_uniforms(s.splat, &splat_rng);
  CornerUniforms* corners = s.splat == Splat::trilinear ? nullptr : &corner_uniforms;
  if (hero) {
    // Photon i of the source's n has hero i mod 3; a_j = (photons with hero j) / n.
    const size_t i = k - first[src], count = first[src + 1] - first[src];
    Rgb share;
    for (int h = 0; h < 3; ++h) share[h] = double((count + 2 - size_t(h)) / 3) / double(count);
    trace_hero(ph, int(i % 3), share, block, first_order, corners, rng, batch);
    return;
  }
  trace_channel(ph, c, block, first_order, corners, rng, batch);
}

void ScatterPhotons::trace_channel(const Photon& ph, int c, const TallyBlock& block, int first_order,
                                   CornerUniforms* corners, Rng& rng, PhotonBatch& batch) const {
  Rgb power = ph.power;
  if (!grey)
    for (int k = 0; k < 3; ++k)
      if (k != c) power[k] = 0.0;
  if (max_component(power) <= 0.0 || !(ph.weight > 0.0)) return;
  double weight = ph.weight;
  int order = 0;  // wide scatters so far
  // The media's values at the last tentative collision, when it looked them up: a real one scatters there
  // next (walk_photon), and reads them instead of looking the density up again. (Not in emitting media,
  // where eval also finds the emission.)
  MediumPoint at_collision;
  bool known = false;
  const bool from_point = values_at_collisions();
  walk_photon(
      ctx, s.majorants ? *s.majorants : ctx.majorants, ph.x, ph.w, majorant_scale, rng, &batch.collisions,
      [&](const Vec3& p, double maj) {
        // Over one grey constant-density shape's exact piece every tentative collision is real (sigma =
        // maj): the uniform is drawn as for any other, the density is not looked up (exact_pieces).
        known = !exact_pieces && from_point;
        if (known) ctx.media.eval(p, &at_collision);
        const double sigma = exact_pieces ? maj : known ? extinction(at_collision)[c] : extinction(p)[c];
        const bool real = rng.uniform() * maj < sigma;
        batch.null_collisions += real ? 0.0 : 1.0;
        return real;
      },
      [&](const Vec3& x, const Vec3& w, double t_end) {
        if (order >= first_order) deposit(batch, block, x, w, t_end, power * weight, corners, rng);
      },
      [&](const Vec3& xc, Vec3* w) {
        return scatter(xc, w, c, &weight, &order, rng, batch, known ? &at_collision : nullptr);
      },
      [&](const SurfaceHit& hit, Vec3* w) { return reflect(hit, w, c, &weight, &order, rng); });
}

// A diffuse reflection's new direction from a mixture: with probability kTowardMedia uniform in the cone of
// the media's sphere (from outside it), else cosine-weighted. *factor: the BRDF's cos / pi over the
// mixture's density (times the albedo, the photon's weight). Most of the light a wide ground reflects
// misses the media; the cone sends half of it their way (a photon of emit_with_surfaces' far plane
// reaches them at all only so). False: the direction is below the surface.
bool ScatterPhotons::bounce(const SurfaceHit& hit, Vec3* w, double* factor, Rng& rng) const {
  constexpr double kTowardMedia = 0.5;
  const Vec3 to_c = centre - hit.p;
  const double dist = to_c.length();
  const double toward = dist > radius ? kTowardMedia : 0.0;
  const double cos_max =
      toward > 0.0 ? std::sqrt(std::max(0.0, 1.0 - radius * radius / (dist * dist))) : -1.0;
  const Vec3 axis = toward > 0.0 ? to_c / dist : hit.ns;
  const double v0 = rng.uniform(), v1 = rng.uniform(), v2 = rng.uniform();
  *w = v0 < toward ? spherical_direction(1.0 - v1 * (1.0 - cos_max), 2.0 * kPi * v2, axis)
                   : cosine_direction(hit.ns, v1, v2);
  const double cos_n = dot(*w, hit.ns);
  if (!(cos_n > 0.0) || !(dot(*w, hit.ng) > 0.0)) return false;
  const bool in_cone = toward > 0.0 && dot(*w, axis) >= cos_max;
  const double pdf = (1.0 - toward) * cos_n / kPi + (in_cone ? toward / (2.0 * kPi * (1.0 - cos_max)) : 0.0);
  *factor = (cos_n / kPi) / pdf;
  return true;
}

// A photon of channel c meets a surface: a diffuse one reflects it (a wide scatter: its albedo times
// bounce's factor as weight, with roulette, a direction on the side it came from); a holdout absorbs it.
bool ScatterPhotons::reflect(const SurfaceHit& hit, Vec3* w, int c, double* weight, int* order,
                             Rng& rng) const {
  const auto* diffuse = std::get_if<DiffuseMaterial>(&ctx.surfaces.material(hit.surface));
  double factor = 0.0;
  if (!diffuse || ++*order >= K || !bounce(hit, w, &factor, rng)) return false;
  *weight *= diffuse->albedo[c] * factor;
  if (*weight < 0.1) {
    if (rng.uniform() * 0.1 >= *weight) return false;
    *weight = 0.1;
  }
  return true;
}

// A real collision at xc of a photon of channel c: albedo weight, roulette, medium, direction.
// False ends the photon.
bool ScatterPhotons::scatter(const Vec3& xc, Vec3* w, int c, double* weight, int* order, Rng& rng,
                             PhotonBatch& batch, const MediumPoint* at_xc) const {
  MediumPoint looked_up;
  if (!at_xc) ctx.media.eval(xc, &looked_up);
  const MediumPoint& mp = at_xc ? *at_xc : looked_up;
  const ScatteringShares shares = scattering_shares(
      mp, ctx.media.count(), c, [&](int i) { return s.exact_transport ? 1.0 : 1.0 - peak_fraction[i]; });
  const double sigma = mp.sigma_a[c] + shares.sum;
  if (!(shares.sum > 0.0) || !(sigma > 0.0)) return false;
  NIMBUS_DCHECK(shares.sum / sigma <= 1.0 + 1e-12);  // an albedo, in [0, 1]
  *weight *= shares.sum / sigma;
  if (*weight < 0.1) {
    if (rng.uniform() * 0.1 >= *weight) return false;
    *weight = 0.1;
  }
  return turn(choose_medium(shares, rng), w, order, rng, batch);
}

// A real collision's new direction in medium m (exact transport: a phase sample and its peak or wide
// class; similarity: a wide scatter). False ends the photon (its K-th wide scatter).
bool ScatterPhotons::turn(int m, Vec3* w, int* order, Rng& rng, PhotonBatch& batch) const {
  const Phase& phase = ctx.media.phase(m);
  // The probability that a scatter into direction cosine mu is a wide one: (1 - f) P_wide / P.
  auto wide_share = [&](double mu) { return splits[m]->wide_share(mu); };
  if (s.exact_transport) {
    // The full phase function; the scatter counts as wide with its share.
    const double v1 = rng.uniform(), v2 = rng.uniform();
    const Vec3 w_new = phase_sample(phase, *w, v1, v2);
    if (rng.uniform() < wide_share(dot(w_new, *w)) && ++*order >= K) return false;
    *w = w_new;
    return true;
  }
  // Peak scatters are not events: draw P_wide by rejection from P (expected 1 / (1 - f) tries).
  if (++*order >= K) return false;
  const bool drawn = sample_by_rejection(
      w,
      [&] {
        const double v1 = rng.uniform(), v2 = rng.uniform();
        return phase_sample(phase, *w, v1, v2);
      },
      [&](const Vec3& candidate) { return rng.uniform() < wide_share(dot(candidate, *w)); });
  if (!drawn) ++batch.rejection_failures;  // the photon flies on undeflected (see sample_by_rejection)
  return true;
}

// A photon of chromatic media with hero channel `hero` (HeroWalk): its power in all three channels,
// deposits weighted by W.
void ScatterPhotons::trace_hero(const Photon& ph, int hero, const Rgb& share, const TallyBlock& block,
                                int first_order, CornerUniforms* corners, Rng& rng,
                                PhotonBatch& batch) const {
  if (max_component(ph.power) <= 0.0 || !(ph.weight > 0.0) || !(share[hero] > 0.0)) return;
  HeroWalk walk{.c = hero, .a = share, .beta = Rgb(ph.weight), .r = Rgb(1.0), .sigma = Rgb(0.0)};
  int order = 0;  // wide scatters so far
  // A flight's track at distance t is weighted by the null collisions before t only: each null
  // collision ends a segment, deposited with the weight it had (weighting the whole flight by the
  // weight at its end biases the channels: the denser ones ~10 % low in the test's sphere).
  Vec3 seg = ph.x;  // where the current segment starts (on the current flight)
  const auto deposit_segment = [&](const Vec3& w, double len) {
    if (order >= first_order) deposit(batch, block, seg, w, len, ph.power * walk.weight(), corners, rng);
  };
  Vec3 dir = ph.w;  // the current flight's direction
  // The media's values at the last tentative collision (as trace_channel; not in emitting media).
  MediumPoint at_collision;
  const bool from_point = values_at_collisions();
  walk_photon(
      ctx, s.majorants ? *s.majorants : ctx.majorants, ph.x, ph.w, majorant_scale, rng, &batch.collisions,
      [&](const Vec3& p, double maj) {
        // A tentative collision: real with probability sigma_c / maj; a null one weights channel k by
        // (maj - sigma_k) / (maj - sigma_c) and technique j's density likewise.
        if (from_point) ctx.media.eval(p, &at_collision);
        walk.sigma = from_point ? extinction(at_collision) : extinction(p);
        NIMBUS_DCHECK(max_component(walk.sigma) <= maj * (1.0 + 1e-9) && min_component(walk.sigma) >= 0.0);
        if (rng.uniform() * maj < walk.sigma[walk.c]) return true;
        batch.null_collisions += 1.0;
        deposit_segment(dir, (p - seg).length());
        seg = p;
        const Rgb null_density(std::max(0.0, maj - walk.sigma.x), std::max(0.0, maj - walk.sigma.y),
                               std::max(0.0, maj - walk.sigma.z));
        walk.update(null_density, null_density);
        return false;
      },
      [&](const Vec3& x, const Vec3& w, double t_end) {
        // The flight's last segment (t_end infinite: the photon leaves; deposit_flight clips it).
        deposit_segment(w, t_end - (seg - x).length());
      },
      [&](const Vec3& xc, Vec3* w) {
        if (!scatter_hero(xc, w, walk, &order, rng, batch, from_point ? &at_collision : nullptr))
          return false;
        seg = xc, dir = *w;
        return true;
      },
      [&](const SurfaceHit& hit, Vec3* w) {
        // A diffuse surface: a wide scatter weighted by its albedo per channel (as reflect, bounce).
        const auto* diffuse = std::get_if<DiffuseMaterial>(&ctx.surfaces.material(hit.surface));
        double factor = 0.0;
        if (!diffuse || ++order >= K || !bounce(hit, w, &factor, rng)) return false;
        walk.beta = walk.beta * diffuse->albedo * factor;
        if (!walk.roulette(rng)) return false;
        seg = SceneSurfaces::offset(hit, *w), dir = *w;  // where walk_photon's next flight starts
        return true;
      });
}

// A real collision of a hero-channel photon at xc: the medium by the hero's scattering shares, the
// weights by each channel's scattering in that medium against the hero's density, roulette, direction.
bool ScatterPhotons::scatter_hero(const Vec3& xc, Vec3* w, HeroWalk& walk, int* order, Rng& rng,
                                  PhotonBatch& batch, const MediumPoint* at_xc) const {
  MediumPoint looked_up;
  if (!at_xc) ctx.media.eval(xc, &looked_up);
  const MediumPoint& mp = at_xc ? *at_xc : looked_up;
  const auto kept = [&](int i) { return s.exact_transport ? 1.0 : 1.0 - peak_fraction[i]; };
  ScatteringShares shares[3];
  for (int k = 0; k < 3; ++k) shares[k] = scattering_shares(mp, ctx.media.count(), k, kept);
  const int c = walk.c;
  if (!(shares[c].sum > 0.0) || !(walk.sigma[c] > 0.0)) return false;
  const int m = choose_medium(shares[c], rng);
  // Per tentative collision (the common 1 / maj dropped): f_k = kept sigma_s,m[k]; p_j = sigma_j x
  // (medium m's share of channel j's scattering), sigma_j the extinction tracked for channel j.
  Rgb f, p;
  for (int k = 0; k < 3; ++k) {
    f[k] = shares[k].part[m];
    p[k] = shares[k].sum > 0.0 ? walk.sigma[k] * shares[k].part[m] / shares[k].sum : 0.0;
  }
  walk.update(f, p);
  if (!walk.roulette(rng)) return false;
  return turn(m, w, order, rng, batch);
}

// The photons of each source (numbered as ScatterPhotons::trace numbers them) as first[i] ..
// first[i + 1] - 1 of a pass: a share s.power_share p_i / sum p + (1 - s.power_share) / sources of
// `photons` (at least 1), p_i the luminance of source i's power towards the media's bounding sphere
// (the mean of 64 of its photons' power, each emitted as the only one; exact for a directional light
// or a constant environment). power_share 1 gives every photon the same power (photon mapping's rule);
// the even part keeps a source of little power from being starved. Which photon belongs to which
// source changes the grid's noise, never its expectation (each source's photons carry its power / n_i).
std::vector<size_t> photon_split(const SceneContext& ctx, const EmissionSampler* emission,
                                 const ScatterGridSettings& s, int photons, size_t lights, size_t sources,
                                 const Vec3& centre, double radius) {
  constexpr int kProbes = 64;
  std::vector<double> power(sources, 0.0);
  double sum = 0.0;
  for (size_t i = 0; i < sources; ++i) {
    const bool from_media = emission && i == sources - 1;
    const size_t source = i < lights ? i : ctx.lights.size();
    for (int k = 0; k < kProbes; ++k) {
      Rng rng(s.seed ^ 0x73706c6974ull, uint64_t(i) * kProbes + uint64_t(k));
      const Photon ph = from_media ? emit_from_media(*emission, ctx.media, 1.0, rng)
                                   : emit(ctx, source, centre, radius, 1.0, rng);
      const double lum = luminance(ph.power);
      if (std::isfinite(lum) && lum > 0.0) power[i] += lum / kProbes;
    }
    sum += power[i];
  }
  const double mix = sum > 0.0 ? std::clamp(s.power_share, 0.0, 1.0) : 0.0;
  std::vector<size_t> first(sources + 1, 0);
  for (size_t i = 0; i < sources; ++i) {
    const double share = (sum > 0.0 ? mix * power[i] / sum : 0.0) + (1.0 - mix) / double(sources);
    first[i + 1] = first[i] + std::max<size_t>(1, size_t(std::llround(share * double(photons))));
  }
  return first;
}

// Per node of `grid`: 1 where a trilinear lookup at a point of non-zero extinction can read it, i.e. a
// corner of a cell that overlaps a cell of non-zero majorant (a conservative bound of the extinction
// everywhere in its cell), else 0. `mfs` reads the grid only where a medium scatters, so the other
// nodes' values are never read (unless through the pre-filtered levels); on the Disney cloud 36 % of
// the nodes are live.
std::vector<uint8_t> live_nodes(const NodeGrid& grid, const MajorantGrid& majorants) {
  std::vector<uint8_t> live(grid.size(), 0);
  const auto r = majorants.resolution();
  const Bounds b = majorants.bounds();
  if (b.empty()) return live;
  const Vec3 cell = (b.hi - b.lo) / Vec3(r[0], r[1], r[2]);
  for (int z = 0; z < r[2]; ++z)
    for (int y = 0; y < r[1]; ++y)
      for (int x = 0; x < r[0]; ++x) {
        if (!(majorants.cell_majorant(x, y, z) > 0.0)) continue;
        const Vec3 lo = b.lo + Vec3(x, y, z) * cell, hi = lo + cell;
        int i0[3], i1[3];  // the node cells it overlaps (widened by 1e-6 of a spacing against rounding)
        for (int a = 0; a < 3; ++a) {
          const double s0 = (lo[a] - grid.bounds.lo[a]) / grid.spacing[a] - 1e-6;
          const double s1 = (hi[a] - grid.bounds.lo[a]) / grid.spacing[a] + 1e-6;
          i0[a] = std::clamp(int(std::floor(s0)), 0, grid.nodes[a] - 2);
          i1[a] = std::clamp(int(std::floor(s1)), 0, grid.nodes[a] - 2);
        }
        for (int k = i0[2]; k <= i1[2]; ++k)
          for (int j = i0[1]; j <= i1[1]; ++j)
            for (int i = i0[0]; i <= i1[0]; ++i)
              for (int c = 0; c < 8; ++c) live[grid.index(i + (c & 1), j + (c >> 1 & 1), k + (c >> 2))] = 1;
      }
  return live;
}

// adaptive_photons (scatter_grid.h): the pilot's photons, and the collisions per photon at which the
// grid keeps settings.photons. On the validation suite (128 x 128, `mfs` 1 spp) error^2 x CPU is least
// at about 2^18 photons on the optically thick spheres, the box and the Disney cloud (3.4 to 4.4
// collisions per photon), 2^19 on the r = 2 sphere (0.89) and 2^20 on the r = 1 sphere (0.44)
// (docs/benchmarks.md, "Photons by collisions"). `mfs` scales its image size's count by the same factor.
// The collisions counted are the tracking's work: the real ones and the null ones (none over the exact
// pieces of constant-density shapes). A photon in a heterogeneous medium meets many null collisions, and
// it is they that make it dear: the thin Disney cloud (0.82 real collisions per photon) took 2.04 x 2^18
// photons by its real collisions alone, which cost more than they bought (error^2 x CPU 0.79x with 2^18 at
// 128 x 128, 1.20x with 2.2 M against 2^20 at 512 x 512; docs/benchmarks.md, "The thin Disney cloud").
// The factor goes down to 1/2 where photons are dearer still (docs/benchmarks.md, "Photons by collisions in
// dense media"; 128 x 128, 6 seeds): the Disney cloud (6.9 collisions per photon, real and null) at 0.70 x
// 2^18 0.87x error^2 x CPU, the r = 50 sphere (21) at 2^17 0.84x and 0.87x; the r = 10 spheres and the box
// (4.2 to 4.8) at 0.84-0.90 x 2^18 0.97-1.05x.
constexpr int kPilotPhotons = 2048;
constexpr double kDenseCollisions = 3.4;
constexpr double kMinPhotonFactor = 0.5;
constexpr double kMaxPhotonFactor = 4.0;

// Per light: light_footprint for a directional light and point_light_footprint for a point light of a scene
// without surfaces (whose light also reaches the media by way of the surfaces, emit_with_surfaces), else none.
std::vector<std::optional<LightFootprint>> light_footprints(const SceneContext& ctx,
                                                            const MajorantGrid& majorants, const Vec3& centre,
                                                            double radius) {
  std::vector<std::optional<LightFootprint>> fp(ctx.lights.size());
  if (!ctx.surfaces.empty()) return fp;
  for (size_t i = 0; i < ctx.lights.size(); ++i)
    if (const auto* d = std::get_if<DirectionalLight>(&ctx.lights[i]))
      fp[i] = light_footprint(majorants, d->direction, centre, radius);
    else if (const auto* p = std::get_if<PointLight>(&ctx.lights[i]))
      fp[i] = point_light_footprint(majorants, p->position, centre, radius);
  return fp;
}

// Whether a pilot sets the count.
bool wants_pilot(const ScatterGridSettings& s) { return s.adaptive_photons > 0 || s.pilot; }

void ScatterPhotons::split(int photons) {
  // The traced lights' footprints only, sources 0 .. lights - 1: with K = 1 the grid traces no light, and its
  // source 0 is the environment.
  if (footprints.empty() && lights > 0) {
    footprints = light_footprints(ctx, s.majorants ? *s.majorants : ctx.majorants, centre, radius);
    footprints.resize(lights);
  }
  first = photon_split(ctx, emission, s, photons, lights, sources, centre, radius);
  planned = first.back();
  std::vector<size_t> count(sources);
  for (size_t i = 0; i < sources; ++i) {
    count[i] = first[i + 1] - first[i];
    if (i < footprints.size() && footprints[i])
      count[i] = std::max<size_t>(1, size_t(std::llround(footprints[i]->share * double(count[i]))));
  }
  for (size_t i = 0; i < sources; ++i) first[i + 1] = first[i] + count[i];
  if (!ctx.surfaces.empty()) surface = surface_emission(ctx, centre, radius);
}

// Real and null collisions per photon of kPilotPhotons photons of a pass (photons.first is left split for
// them), traced serially on streams of their own, their flights not deposited (ScatterPhotons::deposits).
double pilot_collisions(ScatterPhotons& photons, size_t tally_size) {
  photons.split(kPilotPhotons);
  photons.deposits = false;
  ZeroedFloats tally(tally_size);
  PhotonBatch batch;
  batch.tally = {tally.data(), tally_size};
  const size_t n = photons.first.back();
  for (size_t j = 0; j < n; ++j) {
    Rng rng(photons.s.seed ^ 0x70696c6f74ull, j);
    photons.trace(j, rng, batch);
  }
  photons.deposits = true;
  // Per photon of emit's disc (the footprints' photons stand for planned / n as many).
  return (batch.collisions + batch.null_collisions) / double(photons.planned);
}

// s.adaptive_photons x clamp(sqrt(kDenseCollisions / collisions), kMinPhotonFactor, kMaxPhotonFactor), at most
// 2^26.
int adaptive_photon_count(const ScatterGridSettings& s, double collisions) {
  const double factor = std::clamp(std::sqrt(kDenseCollisions / std::max(collisions, 1e-3)), kMinPhotonFactor,
                                   kMaxPhotonFactor);
  return int(std::clamp(std::round(double(s.adaptive_photons) * factor), 1.0, double(1 << 26)));
}

// Whether the photons fly over the exact piece of one constant-density shape (walk_photon's `pieces`: the
// scene's analytic media and majorants) with the full, grey extinction as its majorant: then every
// tentative collision is a real one (ScatterPhotons::exact_pieces). Not for a lone pure absorber, whose
// piece's majorant is twice its extinction (AnalyticMedia).
bool exact_pieces(const SceneContext& ctx, const ScatterGridSettings& s) {
  if (!ctx.analytic.active() || (s.majorants && s.majorants != &ctx.majorants) || !s.exact_transport ||
      ctx.media.count() != 1)
    return false;
  const Medium& m = ctx.media.medium(0);
  const Rgb sigma_t = m.sigma_s + m.sigma_a;
  return max_component(m.sigma_s) > 0.0 && sigma_t.x == sigma_t.y && sigma_t.y == sigma_t.z;
}

// Whether some medium scatters.
bool any_scatters(const SceneMedia& media) {
  for (int i = 0; i < media.count(); ++i)
    if (max_component(media.medium(i).sigma_s) > 0.0) return true;
  return false;
}

// The photons' batches summed and divided by the node volume (fluence and flux); with s.denoise, denoised
// (grid_denoise.h) by the batches' shares of each channel's l = 0 coefficient.
FloatArray sum_batches(const SceneContext& ctx, const ScatterGridSettings& s, const NodeGrid& grid,
                       TallyFold fold, int channels, int coeffs, size_t total, size_t tally_size,
                       const TracePhoton& trace, uint64_t* rejection_failures) {
  for (int ch = 0; s.denoise && ch < channels; ++ch) fold.probes.push_back(ch * coeffs);
  FloatArray per_batch;
  FloatArray values =
      trace_photons_folded(total, s.seed ^ 0x6d756c7469706c65ull, tally_size, 1.0 / grid.cell_volume(), fold,
                           trace, rejection_failures, s.denoise ? &per_batch : nullptr);
  if (s.denoise)
    denoise_grid(&values, grid, channels * coeffs, per_batch, kPhotonBatches, fold.probes,
                 nodes_inside(grid, ctx.media));
  return values;
}

}  // namespace

ScatterGrid::ScatterGrid(const SceneContext& ctx, const std::vector<const PhaseSplit*>& splits,
                         const std::vector<double>& peak_fraction, const ScatterGridSettings& s)
    : bands_(std::clamp(s.bands, 1, kShMaxBands)),
      coeffs_(bands_ * bands_),
      lobe_tail_(s.lobe_tail && bands_ == 3),
      photons_(s.photons) {
  const Bounds media_bounds = ctx.media.bounds();
  if (media_bounds.empty()) {
    values_.assign(grid_.size() * channels_ * coeffs_, 0.0f);  // the default grid: 2^3 nodes over [0, 1]^3
    return;
  }
  grid_ = node_grid_padded(media_bounds, s.resolution > 0 ? s.resolution : 32, ctx.majorants.mean_majorant());
  // With K = 1 only the environment's unscattered-by-wide light is needed (see the header).
  if (!(s.max_wide_scatters == 1 && !ctx.has_environment && !ctx.media.emits()))
    trace(ctx, splits, peak_fraction, s);
  // No photons: zero. (Not filled before tracing: the photons' sum replaces values_, and a zero-fill of
  // the 10 MB grid was a measurable part of the set-up's page faults; issue 12.)
  if (values_.empty()) values_.assign(grid_.size() * channels_ * coeffs_, 0.0f);
}

void ScatterGrid::trace(const SceneContext& ctx, const std::vector<const PhaseSplit*>& splits,
                        const std::vector<double>& peak_fraction, const ScatterGridSettings& s) {
  // Grey media (every coefficient equal in all channels) take one pass carrying RGB power; otherwise
  // one pass per channel with that channel's coefficients.
  const bool grey = grey_media(ctx);
  const bool hero = !grey && !s.channel_passes;
  const int passes = grey || hero ? 1 : 3;
  const size_t lights = s.max_wide_scatters == 1 ? 0 : ctx.lights.size();  // K = 1: environment only
  // The media's emission is one more source, with its share of the photons (emit_from_media).
  // (Only where a medium scatters does the grid's light reach the camera.)
  const EmissionSampler emission = any_scatters(ctx.media) ? EmissionSampler(ctx.media) : EmissionSampler();
  const size_t sources = lights + (ctx.has_environment ? 1 : 0) + (emission.active() ? 1 : 0);
  if (sources == 0 || s.photons <= 0) return;
  const Bounds media_bounds = ctx.media.bounds();
  const Vec3 extent = media_bounds.hi - media_bounds.lo;
  ScatterPhotons photons{
      .ctx = ctx,
      .splits = splits,
      .peak_fraction = peak_fraction,
      .s = s,
      .grid = grid_,
      .live = nullptr,
      .bands = bands_,
      .grey = grey,
      .hero = hero,
      .lights = lights,
      .sources = sources,
      .first = {},
      .emission = emission.active() ? &emission : nullptr,
      .centre = (media_bounds.lo + media_bounds.hi) * 0.5,
      .radius = 0.5 * extent.length() * (1.0 + 1e-9) + 1e-12,
      .K = s.max_wide_scatters <= 0 ? kMaxWideScatters : std::min(s.max_wide_scatters, kMaxWideScatters),
      .majorant_scale =
          s.exact_transport ? 1.0 : majorant_share(ctx.media, [&](int i) { return 1.0 - peak_fraction[i]; }),
      .exact_pieces = exact_pieces(ctx, s),
      .blocks = {}};
  const std::vector<uint8_t> live = s.live_nodes_only
                                        ? live_nodes(grid_, s.majorants ? *s.majorants : ctx.majorants)
                                        : std::vector<uint8_t>();
  photons.live = live.empty() ? nullptr : live.data();
  size_t rgb_size = 0;
  const size_t tally_size =
      assign_blocks(ctx, grey, lights, sources, grid_.size(), coeffs_, &photons.blocks, &rgb_size);
  if (wants_pilot(s)) {
    collisions_per_photon_ = pilot_collisions(photons, tally_size);
    if (s.adaptive_photons > 0) photons_ = adaptive_photon_count(s, *collisions_per_photon_);
  }
  photons.split(photons_);
  const size_t total = size_t(passes) * photons.first.back();
  // Every source of one colour (grey media lit by lights of one tint): one channel per node, the tint
  // kept aside (evaluate multiplies it back in).
  const std::optional<Rgb> tint = common_colour(photons.blocks, rgb_size);
  channels_ = tint ? 1 : 3;
  tint_ = tint.value_or(Rgb(1.0));
  values_ = sum_batches(
      ctx, s, grid_, tally_fold(photons.blocks, rgb_size, coeffs_, grid_.size(), channels_), channels_,
      coeffs_, total, tally_size,
      [&](size_t j, Rng& rng, PhotonBatch& batch) { photons.trace(j, rng, batch); }, &rejection_failures_);
  if (s.prefiltered) build_mips();
}

void ScatterGrid::build_mips() {
  // Each level halves the node count along every axis (nodes 2j of the level below), with the tent
  // filter (1/4, 1/2, 1/4) per axis; nodes beyond the level below's last are clamped to it.
  const int floats = channels_ * coeffs_;
  const NodeGrid* below = &grid_;
  const float* src = values_.data();
  while (std::max({below->nodes[0], below->nodes[1], below->nodes[2]}) > 4 && mips_.size() < 4) {
    Level lv;
    lv.grid.bounds.lo = grid_.bounds.lo;
    for (int a = 0; a < 3; ++a) {
      lv.grid.nodes[a] = std::max(2, (below->nodes[a] + 2) / 2);
      lv.grid.spacing[a] = 2.0 * below->spacing[a];
      lv.grid.bounds.hi[a] = lv.grid.bounds.lo[a] + lv.grid.spacing[a] * (lv.grid.nodes[a] - 1);
    }
    lv.values = tent_downsample(*below, src, lv.grid, floats);
    mips_.push_back(std::move(lv));
    below = &mips_.back().grid;
    src = mips_.back().values.data();
  }
}

void ScatterGrid::accumulate(int level, const Vec3& p, double wt, double* L) const {
  const Level* lv = level > 0 ? &mips_[level - 1] : nullptr;
  accumulate((lv ? lv->grid : grid_).stencil(p), lv ? lv->values.data() : values_.data(), wt, L);
}

void ScatterGrid::accumulate(const TrilinearStencil& st, const float* v, double wt, double* L) const {
  const int floats = channels_ * coeffs_;
  // The same sums with the node's size known at compile time for the default 3 bands (27 floats, or 9
  // for a one-channel grid).
  const auto sum = [&](auto n) {
    for (int k = 0; k < 8; ++k) {
      const float* node = &v[st.node[k] * size_t(n())];
      const double w = wt * st.weight[k];
      for (int h = 0; h < n(); ++h) L[h] += w * node[h];
    }
  };
  if (floats == 27)
    sum([] { return 27; });
  else if (floats == 9)
    sum([] { return 9; });
  else
    sum([floats] { return floats; });
}

Rgb ScatterGrid::evaluate(const double* L, const ShBasis& y_out,
                          const std::array<Rgb, kShMaxBands>& chi) const {
  const double* y = y_out.y;
  double tail[kShMaxBands];
  bool tail_found = false;
  Rgb r;
  for (int c = 0; c < 3; ++c) {
    const double* Lc = L + (channels_ == 1 ? 0 : coeffs_ * c);
    double v = 0.0;
    for (int l = 0; l < bands_; ++l)
      for (int h = l * l; h < (l + 1) * (l + 1); ++h) v += chi[l][c] * Lc[h] * y[h];
    bool tail_read = false;  // chi_l beyond the bands given (mfs.cpp: tail_moments)
    for (int l = bands_; l < kShMaxBands && lobe_tail_; ++l) tail_read = tail_read || chi[l][c] != 0.0;
    if (tail_read) {
      if (!tail_found || channels_ != 1) sh_lobe_tail(Lc, y, tail);  // one-channel grids: the same lobe
      tail_found = true;
      for (int l = bands_; l < kShMaxBands; ++l) v += chi[l][c] * tail[l];
    }
    r[c] = std::max(0.0, tint_[c] * v);
  }
  return r;
}

Rgb ScatterGrid::scattered_filtered(const Vec3& p, const Vec3& w_out, const std::array<Rgb, kShMaxBands>& chi,
                                    double spread) const {
  return scattered_filtered(p, ShBasis(w_out, bands_), chi, spread);
}

Rgb ScatterGrid::scattered_filtered(const Vec3& p, const ShBasis& y_out,
                                    const std::array<Rgb, kShMaxBands>& chi, double spread) const {
  if (!grid_.bounds.contains(p)) return Rgb(0.0);
  const double h = grid_.min_spacing();
  const double level = std::clamp(std::log2(std::max(spread, 1e-300) / h), 0.0, double(mips_.size()));
  if (!(level > 0.0)) return scattered(p, y_out, chi);
  double L[3 * kShMaxBands * kShMaxBands] = {};
  const int k0 = std::min(int(level), int(mips_.size()));
  const double f = level - k0;
  accumulate(k0, p, 1.0 - f, L);
  if (f > 0.0) accumulate(k0 + 1, p, f, L);
  return evaluate(L, y_out, chi);
}

Rgb ScatterGrid::scattered(const Vec3& p, const Vec3& w_out, const std::array<Rgb, kShMaxBands>& chi) const {
  return scattered(p, ShBasis(w_out, bands_), chi);
}

Rgb ScatterGrid::scattered(const Vec3& p, const ShBasis& y_out,
                           const std::array<Rgb, kShMaxBands>& chi) const {
  if (!grid_.bounds.contains(p)) return Rgb(0.0);
  double L[3 * kShMaxBands * kShMaxBands] = {};
  accumulate(0, p, 1.0, L);
  return evaluate(L, y_out, chi);
}

Rgb ScatterGrid::scattered(const Vec3& p, const TrilinearStencil& st, const ShBasis& y_out,
                           const std::array<Rgb, kShMaxBands>& chi) const {
  if (!grid_.bounds.contains(p)) return Rgb(0.0);
  double L[3 * kShMaxBands * kShMaxBands] = {};
  accumulate(st, values_.data(), 1.0, L);
  return evaluate(L, y_out, chi);
}

}  // namespace nimbus
