// The beam grid (integrators/beam_grid.h): its photons (through the shared photon tracer) and its
// lookup.
// long-file: the photons' deposits and the lookup share the node's column layout (Blocks) and the straight
// model's helpers of this file's anonymous namespace; a second file would have to expose them.
#include "integrators/beam_grid.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "core/check.h"
#include "integrators/area_light_view.h"
#include "integrators/photon_tracer.h"

namespace nimbus {

// `passes` times, along each axis in turn, the filter [1 2 1] / 4 over the nodes inside the media: a
// neighbour outside them (or beyond the grid) is left out and the weights renormalised, and the nodes
// outside keep their tallies. Every column alike, so R = traced / straight at a node becomes the ratio of
// the two tallies' local sums: the grid's noise, lines along single photons' deflected paths (streaks in
// thin media, blotches along a backlit rim), is averaged over about one node spacing (two passes: the
// binomial [1 4 6 4 1] / 16, a standard deviation of one spacing) without mixing in the R outside the
// media (the light there scatters no more: beam_smoothing, docs/benchmarks.md).
void smooth_nodes_inside(FloatArray* v, const NodeGrid& g, const std::vector<uint8_t>& inside, int stride,
                         int passes) {
  std::vector<float> before(v->size());
  for (int pass = 0; pass < passes; ++pass)
    for (int a = 0; a < 3; ++a) {
      std::copy(v->begin(), v->end(), before.begin());
      const size_t step = a == 0 ? 1 : a == 1 ? size_t(g.nodes[0]) : size_t(g.nodes[0]) * g.nodes[1];
      for (int z = 0; z < g.nodes[2]; ++z)
        for (int y = 0; y < g.nodes[1]; ++y)
          for (int x = 0; x < g.nodes[0]; ++x) {
            const size_t n = g.index(x, y, z);
            if (!inside[n]) continue;
            const int q = a == 0 ? x : a == 1 ? y : z;
            const bool lo = q > 0 && inside[n - step], hi = q + 1 < g.nodes[a] && inside[n + step];
            const float w = 1.0f / (2.0f + float(lo) + float(hi));
            for (int k = 0; k < stride; ++k) {
              const size_t i = n * size_t(stride) + size_t(k);
              float sum = 2.0f * before[i];
              if (lo) sum += before[i - step * size_t(stride)];
              if (hi) sum += before[i + step * size_t(stride)];
              (*v)[i] = sum * w;
            }
          }
    }
}

std::vector<uint8_t> nodes_inside(const NodeGrid& g, const SceneMedia& media) {
  std::vector<uint8_t> in(g.size(), 0);
  for (int z = 0; z < g.nodes[2]; ++z)
    for (int y = 0; y < g.nodes[1]; ++y)
      for (int x = 0; x < g.nodes[0]; ++x) in[g.index(x, y, z)] = media.inside(g.position(x, y, z));
  return in;
}

namespace {

// Per node, blocks of `channels` floats (3: rgb; 1: grey media under lights of grey strength, whose three
// channels would be the same numbers), in this order: traced, straight; with the spread (beam_spread
// "traced"), traced x (1 - cosine) and straight x the straight model's 1 - mean cosine; with a camera
// (peak_toward), traced x P_peak towards the camera; with the wide factor towards the camera (wide_toward),
// traced x P_wide towards the camera and traced x the straight model's wide_eff there; last, traced and
// straight again, not divided by the straight model's T_wide (their ratio is BeamGrid::lookup's bound).
struct Blocks {
  bool spread, pk, wide = false;
  int count() const { return plain_block() + 2; }
  int pk_block() const { return spread ? 4 : 2; }
  int wide_block() const { return pk_block() + (pk ? 1 : 0); }
  int plain_block() const { return wide_block() + (wide ? 2 : 0); }
};
constexpr double kR2a1 = 0.75487766624669276, kR2a2 = 0.56984029099805327;  // the R2 sequence
constexpr double kRoulette = 0.05;  // roulette below this ratio of weight to T_wide
// Deposit samples (and the loss's midpoint rule) at most this many node spacings apart: 1 (0.5 before,
// 0.25 before that) halves the deposits and density lookups again with no change in the validation
// errors beyond their seed-to-seed spread (docs/benchmarks.md, issue 12: the scatter grid's step too).
// The straight deposit beyond a photon's first peak scatter at 2 spacings moved the means of the box,
// the r2 sphere and the backlit spheres by +1.1 to +2.4 % (its loss no longer matches the traced one's).
constexpr double kDepositStep = 1.0;

// The straight model's mean cosine of the peak-only light, exp(-tau (1 - chi_1)) for its peak depth tau =
// ln(T_wide / T_light) (eq. D3 at l = 1; peak_only_beam's tau_ps): (T_light / T_wide)^(1 - chi_1) per
// channel, 0 where T_wide is 0. Grey transmittances: one pow.
Rgb straight_mean_cosine(const Rgb& full, const Rgb& reduced, double one_minus_chi1) {
  const auto one = [&](int c) {
    return reduced[c] > 1e-30 ? std::pow(std::clamp(full[c] / reduced[c], 0.0, 1.0), one_minus_chi1) : 0.0;
  };
  if (full.x == full.y && full.y == full.z && reduced.x == reduced.y && reduced.y == reduced.z)
    return Rgb(one(0));
  return Rgb(one(0), one(1), one(2));
}

// Which columns a deposit sample goes to.
enum class Columns { traced, straight, both };

// Adds v (channel ch of `channels`) with trilinear weights st to the tally: to the straight column (and
// times spread_s its spread column, times tw its plain column), to the traced one (and times spread its
// spread column, times tw its plain column), or to both;
// with a P_peak block also the traced v times pk (P_peak towards the camera); with the wide blocks the
// traced v times pw (P_wide towards the camera) and times pm (the straight model's wide factor).
struct CameraFactors {
  double pk = 0.0, pw = 0.0, pm = 0.0;
};
void splat(float* tally, int channels, Blocks b, const TrilinearStencil& st, int ch, double v, double tw,
           double spread, double spread_s, const CameraFactors& cf, Columns to) {
  const int stride = channels * b.count();
  const int plain = b.plain_block() * channels;
  for (int j = 0; j < 8; ++j)
    if (st.weight[j] > 0.0) {
      float* node = &tally[st.node[j] * stride + ch];
      const double x = st.weight[j] * v;
      if (to != Columns::traced) {
        node[channels] += float(x);
        node[plain + channels] += float(x * tw);
        if (b.spread) node[3 * channels] += float(x * spread_s);
      }
      if (to != Columns::straight) {
        node[0] += float(x);
        node[plain] += float(x * tw);
        if (b.spread) node[2 * channels] += float(x * spread);
        if (b.pk) node[b.pk_block() * channels] += float(x * cf.pk);
        if (b.wide) {
          node[b.wide_block() * channels] += float(x * cf.pw);
          node[(b.wide_block() + 1) * channels] += float(x * cf.pm);
        }
      }
    }
}

// The cell of the node grid that holds p (clamped into the grid), as an index over the cells (x fastest).
size_t grid_cell(const NodeGrid& g, const Vec3& p) {
  size_t idx = 0;
  for (int a = 2; a >= 0; --a) {
    const double u = std::clamp((p[a] - g.bounds.lo[a]) / g.spacing[a], 0.0, double(g.nodes[a] - 2));
    idx = idx * size_t(g.nodes[a] - 1) + size_t(std::min(int(u), g.nodes[a] - 2));
  }
  return idx;
}

// Per cell of the node grid: 1 where no medium has any extinction in the cell or in the 26 around it (the
// majorant grid's cells there are all 0). A deposit sample in such a cell has no loss (its weight is
// unchanged) and goes only to nodes no cell with a medium touches: nodes `mfs` never reads where a
// medium scatters (a lookup at a point reads the 8 nodes of its cell), so it is skipped, and R and the
// mean cosine stay bit for bit what they were wherever there is a medium. Outside the media (in the
// grid's padding, empty space inside the media's bounds, the shadow behind them) the tallies are
// incomplete; `mfs` multiplies them by sigma_s there, which is 0. Without skip: every cell 0 (none idle).
std::vector<uint8_t> idle_cells(const NodeGrid& g, const MajorantGrid& maj, bool skip) {
  const std::array<int, 3> cells{g.nodes[0] - 1, g.nodes[1] - 1, g.nodes[2] - 1};
  std::vector<uint8_t> idle(size_t(cells[0]) * cells[1] * cells[2], skip ? 1 : 0);
  if (!skip) return idle;
  const std::array<int, 3> res = maj.resolution();
  const Bounds& mb = maj.bounds();
  if (mb.empty()) return idle;
  Vec3 msize;
  for (int a = 0; a < 3; ++a) msize[a] = (mb.hi[a] - mb.lo[a]) / res[a];
  // Each majorant cell with extinction marks the node-grid cells its box (grown by one node spacing, the
  // 26 neighbours) overlaps, and one more on each side for rounding.
  for (int z = 0; z < res[2]; ++z)
    for (int y = 0; y < res[1]; ++y)
      for (int x = 0; x < res[0]; ++x) {
        if (!(maj.cell_majorant(x, y, z) > 0.0)) continue;
        const int m[3] = {x, y, z};
        int lo[3], hi[3];
        for (int a = 0; a < 3; ++a) {
          const double c0 = (mb.lo[a] + m[a] * msize[a] - g.bounds.lo[a]) / g.spacing[a];
          const double c1 = (mb.lo[a] + (m[a] + 1) * msize[a] - g.bounds.lo[a]) / g.spacing[a];
          lo[a] = std::clamp(int(std::floor(c0)) - 2, 0, cells[a] - 1);
          hi[a] = std::clamp(int(std::floor(c1)) + 2, 0, cells[a] - 1);
        }
        for (int k = lo[2]; k <= hi[2]; ++k)
          for (int j = lo[1]; j <= hi[1]; ++j)
            for (int i = lo[0]; i <= hi[0]; ++i) idle[(size_t(k) * cells[1] + j) * cells[0] + i] = 0;
      }
  return idle;
}

// Where a node's straight tally is 0 in a channel (a surface's shadow: the straight line ended at the
// surface), its traced columns are dropped too: light deflected into the shadow (unused there: `mfs` tests
// the shadow itself) would otherwise raise R in the lit medium beside it through the lookups' trilinear
// weights and the smoothing. Without surfaces every node the photons reach has a straight tally.
void drop_unmatched(FloatArray* v, int channels, Blocks b) {
  const size_t stride = size_t(channels) * size_t(b.count());
  for (size_t n = 0; n + stride <= v->size(); n += stride) {
    float* node = v->data() + n;
    for (int c = 0; c < channels; ++c) {
      if (node[channels + c] != 0.0f) continue;
      node[c] = 0.0f;
      if (b.spread) node[2 * channels + c] = 0.0f;
      if (b.pk) node[b.pk_block() * channels + c] = 0.0f;
      if (b.wide) node[b.wide_block() * channels + c] = node[(b.wide_block() + 1) * channels + c] = 0.0f;
      node[b.plain_block() * channels + c] = node[(b.plain_block() + 1) * channels + c] = 0.0f;
    }
  }
}

// Every light's tallies: drop_unmatched, then `passes` of smooth_nodes_inside over the nodes inside the media.
void finish_tallies(std::vector<FloatArray>* values, const NodeGrid& g, const SceneMedia& media, int channels,
                    Blocks b, int passes) {
  bool any = false;
  for (FloatArray& v : *values)
    if (!v.empty()) drop_unmatched(&v, channels, b), any = true;
  if (passes <= 0 || !any) return;
  const std::vector<uint8_t> inside = nodes_inside(g, media);
  for (FloatArray& v : *values)
    if (!v.empty()) smooth_nodes_inside(&v, g, inside, channels * b.count(), passes);
}

// True when every directional and point light's photons carry the same weight in all three channels (a
// strength with no channel at 0, or none at all): with grey media the beam grid's three channels are then
// the same numbers (the same bits under white light), and it keeps one.
bool grey_lights(const SceneContext& ctx) {
  for (const Light& light : ctx.lights) {
    Rgb s(0.0);
    if (const auto* d = std::get_if<DirectionalLight>(&light)) s = d->irradiance;
    if (const auto* p = std::get_if<PointLight>(&light)) s = p->intensity;
    if (!((s.x > 0.0 && s.y > 0.0 && s.z > 0.0) || max_component(s) <= 0.0)) return false;
  }
  return true;
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
  const TransmittanceGrid& T_wide;  // the light's reduced shadow map (empty: the closed-form chord)
  const TransmittanceGrid& T_full;  // its full one, of the same layout (empty: the chord)
  bool chord;                       // T_wide by the chord (one constant-density shape: an empty map)
  double one_minus_chi1;            // 1 - chi_1 of medium 0's peak (the straight model's spread)
  Blocks blocks;                    // the node's columns
  const NodeGrid& grid;
  size_t light;
  const PointLight* point;  // or null: a directional light
  Rgb strength;             // phi_0 = strength (/ r^2)
  Vec3 dir_w;               // a directional light's direction of travel
  bool grey;                // one pass carrying RGB (else one pass per channel)
  size_t per_pass;          // photons per channel pass (all of the light's photons in grey media)
  Vec3 centre;              // of the node grid's bounding sphere, which the photons are aimed at
  double radius;
  double majorant_scale;             // the share of the majorant that bounds the peak-scatter rate
  const Vec3* camera;                // tally P_peak (of medium 0) towards this point, or null
  int channels;                      // floats per column of a node: 3, or 1 (channel 0 stands for all)
  const MajorantGrid* majorants;     // the photons' tracking majorants (null: the scene's)
  const std::vector<uint8_t>& idle;  // per cell of the node grid: see idle_cells

  // T_light and T_wide from q to the light by the chord in closed form (1 where it has none).
  void chord_to_light(const Vec3& q, Rgb* full, Rgb* reduced) const;
  // T_wide from q to the light: the map, or the chord.
  Rgb wide(const Vec3& q) const;
  // T_light and T_wide from q to the light: the maps, or the chord.
  void full_and_wide(const Vec3& q, Rgb* full, Rgb* reduced) const;
  void trace(size_t j, Rng& rng, PhotonBatch& batch) const;
  void sample(float* tally, const Vec3& q, const Vec3& w, double dl, Rgb* weight, int c, Columns to) const;
  Rgb deposit(float* tally, const Vec3& x, const Vec3& w, double t_end, Rgb weight, int c) const;
  Rgb deposit_first(float* tally, const Vec3& x, const Vec3& w, double t_end, Rgb weight, int c) const;
  bool scatter(const Vec3& xc, Vec3* w, BeamWalk& walk, Rng& rng, PhotonBatch& batch) const;
};

void BeamPhotons::chord_to_light(const Vec3& q, Rgb* full, Rgb* reduced) const {
  const double inf = std::numeric_limits<double>::infinity();
  const bool done = point
                        ? chord_full_and_reduced(ctx, q, normalize(point->position - q),
                                                 (point->position - q).length(), peak_fraction, full, reduced)
                        : chord_full_and_reduced(ctx, q, -dir_w, inf, peak_fraction, full, reduced);
  NIMBUS_DCHECK(done);
  if (!done) *full = *reduced = Rgb(1.0);
}

void BeamPhotons::full_and_wide(const Vec3& q, Rgb* full, Rgb* reduced) const {
  if (chord) return chord_to_light(q, full, reduced);
  const TrilinearStencil st = T_wide.stencil(q);  // the pair's shared layout (build_pair)
  *reduced = T_wide.lookup(st);
  *full = T_full.lookup(st);
}

Rgb BeamPhotons::wide(const Vec3& q) const {
  if (!chord) return T_wide.lookup(q);
  Rgb full, reduced;
  chord_to_light(q, &full, &reduced);
  return reduced;
}

// One deposit sample at q (the midpoint of a step of length dl of the flight along w): the weight loses
// exp(-sigma_loss dl) over the step and the midpoint's weight, divided by the straight-line model phi_0
// T_wide at q, goes to the columns `to`. Channel c only unless grey.
void BeamPhotons::sample(float* tally, const Vec3& q, const Vec3& w, double dl, Rgb* weight, int c,
                         Columns to) const {
  // An idle cell: no loss, and its nodes are read by no lookup that matters (idle_cells).
  if (idle[grid_cell(grid, q)]) return;
  const Rgb loss = reduced_sigma_t(ctx.media, q, peak_fraction);
  // exp(-loss dl / 2) once per channel that is deposited (once in all where the channels agree: grey media
  // with a grey weight), the same values as computing all three.
  Rgb half;
  if (grey && loss.x == loss.y && loss.y == loss.z) {
    half = Rgb(std::exp(-loss.x * (0.5 * dl)));
  } else {
    half = Rgb(0.0);
    for (int ch = 0; ch < 3; ++ch)
      if (grey || ch == c) half[ch] = std::exp(-loss[ch] * (0.5 * dl));
  }
  const Rgb mid = *weight * half;
  *weight = mid * half;
  Rgb tw, tf;  // T_wide and (for the straight spread or the wide factor) T_light at q
  const bool spread_s_wanted = blocks.spread && to != Columns::traced;
  const bool wide_wanted = blocks.wide && to != Columns::straight;
  if (spread_s_wanted || wide_wanted)
    full_and_wide(q, &tf, &tw);
  else
    tw = wide(q);
  // The straight model's spread 1 - mean cosine at q, 1 - exp(-tau (1 - chi_1)) for the peak depth tau =
  // ln(T_wide / T_light) (eq. D3 at l = 1).
  const Rgb spread_s = spread_s_wanted ? Rgb(1.0) - straight_mean_cosine(tf, tw, one_minus_chi1) : Rgb(0.0);
  const double geo = point ? 1.0 / std::max(1e-300, dot(q - point->position, q - point->position)) : 1.0;
  const bool traced = to != Columns::straight;
  // 1 - the cosine between the travel direction and the straight one from the light.
  const double spread = !(blocks.spread && traced)
                            ? 0.0
                            : 1.0 - (point ? dot(w, normalize(q - point->position)) : dot(w, dir_w));
  // The peak-only light's last peak scatter towards the camera (the forward-peak term's angular factor).
  CameraFactors cf;
  Vec3 to_camera(0.0);
  if (camera && traced) to_camera = normalize(*camera - q);
  if (blocks.pk && traced) cf.pk = splits[0]->peak(dot(w, to_camera));
  // The wide factor towards the camera: P_wide at the photon's own direction, and the straight model's,
  // wide_eff at the straight beam's peak depth ln(T_wide / T_light) and the straight direction.
  const double mu_s = wide_wanted ? dot(point ? normalize(q - point->position) : dir_w, to_camera) : 0.0;
  if (wide_wanted) cf.pw = splits[0]->wide(dot(w, to_camera));
  const TrilinearStencil st = grid.stencil(q);
  for (int ch = 0; ch < channels; ++ch) {
    if ((!grey && ch != c) || !(tw[ch] > 1e-30)) continue;
    const double v = mid[ch] * dl / (tw[ch] * geo);
    NIMBUS_DCHECK(v >= 0.0 && std::isfinite(v));
    if (wide_wanted)
      cf.pm = splits[0]->wide_eff(
          tf[ch] > 1e-30 ? std::max(0.0, std::log(tw[ch] / tf[ch])) : PhaseSplit::kTauMax, mu_s);
    splat(tally, channels, blocks, st, ch, v, tw[ch], spread, spread_s[ch], cf, to);
  }
}

// Track-length deposit of a traced flight x + t w, t in [0, t_end] (clipped to the grid), starting with
// `weight` (channel c only unless grey) and losing exp(-int sigma_loss) along the way (midpoint rule at
// the deposit samples, at most kDepositStep node spacings apart); each sample divided by the
// straight-line model at that point. Returns the weight at t_end.
Rgb BeamPhotons::deposit(float* tally, const Vec3& x, const Vec3& w, double t_end, Rgb weight, int c) const {
  double t0, t1;
  if (!grid.bounds.intersect(x, w, 0.0, t_end, &t0, &t1) || !(t1 - t0 > 0.0)) return weight;
  const double len = t1 - t0;
  const int n = std::max(1, int(std::ceil(len / (kDepositStep * grid.min_spacing()))));
  const double dl = len / n;
  for (int k = 0; k < n; ++k)
    sample(tally, x + w * (t0 + (k + 0.5) * dl), w, dl, &weight, c, Columns::traced);
  return weight;
}

// A photon's first flight (from its emission, up to its first peak scatter at t_end) together with the
// straight deposit: the same photon undeflected through the whole grid (the model itself with the same
// emission: a control variate; R = traced / straight cancels the emission's sampling noise and the
// difference between the midpoint rule's loss and the shadow map). Until t_end the two are the same
// flight, so they share the samples (one density and one shadow-map lookup for both columns), laid out
// over the straight chord at most kDepositStep apart; the traced flight's last, partial step takes a
// sample of its own. A photon that never scatters deposits the same samples in both columns, so R is 1
// to rounding wherever nothing deflects the light. Beyond the first peak scatter the straight deposit
// goes on alone on the same samples.
// Returns the traced weight at t_end.
Rgb BeamPhotons::deposit_first(float* tally, const Vec3& x, const Vec3& w, double t_end, Rgb weight,
                               int c) const {
  double t0, t1;
  // The straight line ends at the first surface on it, as the straight model's light does (`mfs` tests a
  // surface's shadow on its own): in a surface's shadow both columns are empty, not R = 0.
  SurfaceHit hit;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const double t_max = !ctx.surfaces.empty() && ctx.surfaces.intersect(x, w, kInf, &hit) ? hit.t : kInf;
  if (!grid.bounds.intersect(x, w, 0.0, t_max, &t0, &t1) || !(t1 - t0 > 0.0)) return weight;
  const double len = t1 - t0;
  const int n = std::max(1, int(std::ceil(len / (kDepositStep * grid.min_spacing()))));
  const double dl = len / n;
  // Whole steps before t_end: shared.
  int k = 0;
  for (; k < n && t0 + (k + 1) * dl <= t_end; ++k)
    sample(tally, x + w * (t0 + (k + 0.5) * dl), w, dl, &weight, c, Columns::both);
  if (k == n) return weight;  // the photon left the grid unscattered
  Rgb straight = weight;
  // The traced flight's partial step [t0 + k dl, t_end].
  const double ts = t0 + k * dl, part = std::min(t_end, t1) - ts;
  if (part > 0.0) sample(tally, x + w * (ts + 0.5 * part), w, part, &weight, c, Columns::traced);
  // The rest of the straight chord: its own samples from step k on.
  for (; k < n; ++k) sample(tally, x + w * (t0 + (k + 0.5) * dl), w, dl, &straight, c, Columns::straight);
  return weight;
}

void BeamPhotons::trace(size_t j, Rng& rng, PhotonBatch& batch) const {
  BeamWalk walk;
  walk.c = int(j / per_pass);
  const size_t k = j % per_pass;
  double strat[2] = {0.5 + k * kR2a1, 0.5 + k * kR2a2};
  for (double& u : strat) u -= std::floor(u);
  const Photon ph = emit(ctx, light, centre, radius, double(per_pass), rng, strat);
  // Power per photon over phi_0's strength: the geometry of the emission only.
  walk.weight = Rgb(0.0);
  for (int ch = 0; ch < 3; ++ch)
    if ((grey || ch == walk.c) && strength[ch] > 0.0) walk.weight[ch] = ph.power[ch] / strength[ch];
  if (max_component(walk.weight) <= 0.0) return;
  walk.w0 = walk.weight[walk.c];
  // The first flight also deposits the same photon undeflected (deposit_first).
  bool first = true;
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
        walk.weight = first ? deposit_first(batch.tally.data(), x, w, t_end, walk.weight, walk.c)
                            : deposit(batch.tally.data(), x, w, t_end, walk.weight, walk.c);
        first = false;
      },
      [&](const Vec3& xc, Vec3* w) { return scatter(xc, w, walk, rng, batch); },
      // A reflection is a wide scatter: not part of the forward-peaked beam.
      [](const SurfaceHit&, Vec3*) { return false; });
}

// A peak scatter at xc: roulette, medium, direction (from P_peak). False ends the photon.
bool BeamPhotons::scatter(const Vec3& xc, Vec3* w, BeamWalk& walk, Rng& rng, PhotonBatch& batch) const {
  const int c = walk.c;
  // Roulette on the ratio to the model (what is deposited), not on the weight alone.
  const double tw = wide(xc)[c] * walk.w0;
  if (tw > 0.0 && walk.weight[c] < kRoulette * tw) {
    const double keep = walk.weight[c] / (kRoulette * tw);
    NIMBUS_DCHECK(keep >= 0.0 && keep < 1.0);
    if (rng.uniform() >= keep) return false;
    walk.weight *= 1.0 / keep;
  }
  // walk.mp holds the media's values at xc: the tentative collision that made this scatter real looked them up.
  const ScatteringShares shares =
      scattering_shares(walk.mp, ctx.media.count(), c, [&](int i) { return peak_fraction[i]; });
  if (!(shares.sum > 0.0)) return false;
  const int m = choose_medium(shares, rng);
  const Phase& phase = ctx.media.phase(m);
  // P_peak by rejection from P: accept with f P_peak / P (expected 1 / f tries).
  const bool drawn = sample_by_rejection(
      w,
      [&] {
        // u2 first: the order GCC gave phase_sample(phase, w, rng.uniform(), rng.uniform()) before.
        const double u2 = rng.uniform(), u1 = rng.uniform();
        return phase_sample(phase, *w, u1, u2);
      },
      [&](const Vec3& candidate) {
        // f P_peak / P = 1 - the wide share.
        return rng.uniform() < 1.0 - splits[m]->wide_share(dot(candidate, *w));
      });
  if (!drawn) ++batch.rejection_failures;  // the photon flies on undeflected (see sample_by_rejection)
  return true;
}

}  // namespace

BeamGrid::BeamGrid(const SceneContext& ctx, const std::vector<const PhaseSplit*>& splits,
                   const std::vector<double>& peak_fraction, const std::vector<TransmittanceGrid>& full_maps,
                   const std::vector<TransmittanceGrid>& reduced_maps, const std::vector<int>& photons,
                   int resolution, uint64_t seed, bool spread, const Vec3* camera,
                   const MajorantGrid* majorants, bool skip_idle, int smoothing, BeamCameraTallies tallies)
    : with_camera_(camera != nullptr && tallies.peak),
      with_wide_(camera != nullptr && tallies.wide),
      spread_(spread) {
  if (camera) camera_ = *camera;
  values_.resize(ctx.lights.size());
  const Bounds media_bounds = ctx.media.bounds();
  if (media_bounds.empty() || photons.size() != ctx.lights.size() ||
      std::none_of(photons.begin(), photons.end(), [](int n) { return n > 0; }) ||
      reduced_maps.size() != ctx.lights.size() || full_maps.size() != ctx.lights.size() || splits.empty())
    return;
  one_minus_chi1_ = 1.0 - (splits[0]->peak_moments().size() > 1 ? splits[0]->peak_moments()[1] : 1.0);
  grid_ = node_grid_padded(media_bounds, resolution, ctx.majorants.mean_majorant());
  const bool grey = grey_media(ctx);
  channels_ = grey && grey_lights(ctx) ? 1 : 3;
  const Blocks blocks{.spread = spread, .pk = with_camera_, .wide = with_wide_};
  stride_ = channels_ * blocks.count();
  const Vec3 centre = (media_bounds.lo + media_bounds.hi) * 0.5;
  // Photons cover the whole node grid (its padding included), so every node's estimate is complete.
  const double radius = 0.5 * (grid_.bounds.hi - grid_.bounds.lo).length() * (1.0 + 1e-9) + 1e-12;
  const std::vector<uint8_t> idle = idle_cells(grid_, ctx.majorants, skip_idle);
  idle_share_ = double(std::count(idle.begin(), idle.end(), uint8_t(1))) / double(idle.size());
  const double scale = majorant_share(ctx.media, [&](int i) { return peak_fraction[i]; });
  for (size_t l = 0; l < ctx.lights.size(); ++l) {
    const Light& light = ctx.lights[l];
    const auto* dir = std::get_if<DirectionalLight>(&light);
    const auto* point = std::get_if<PointLight>(&light);
    if ((!dir && !point) || photons[l] <= 0) continue;
    // Chromatic media: one pass per channel, the light's photons shared among them (a third each: the
    // suite's chromatic box had the same error with a third as with all three times over, at 0.8x the
    // set-up; docs/benchmarks.md).
    const size_t per_pass = grey ? size_t(photons[l]) : std::max<size_t>(1, (size_t(photons[l]) + 2) / 3);
    const size_t total = size_t(grey ? 1 : 3) * per_pass;
    const BeamPhotons beam{.ctx = ctx,
                           .splits = splits,
                           .peak_fraction = peak_fraction,
                           .T_wide = reduced_maps[l],
                           .T_full = full_maps[l],
                           .chord = reduced_maps[l].memory_bytes() == 0,
                           .one_minus_chi1 = one_minus_chi1_,
                           .blocks = blocks,
                           .grid = grid_,
                           .light = l,
                           .point = point,
                           .strength = dir ? dir->irradiance : point->intensity,
                           .dir_w = dir ? normalize(dir->direction) : Vec3(0.0),
                           .grey = grey,
                           .per_pass = per_pass,
                           .centre = centre,
                           .radius = radius,
                           .majorant_scale = scale,
                           .camera = camera ? &camera_ : nullptr,
                           .channels = channels_,
                           .majorants = majorants,
                           .idle = idle};
    // The batches' sums divided by the node volume.
    values_[l] = trace_photons(
        total, seed ^ 0x7065616b6265616dull ^ (uint64_t(l) << 40), grid_.size() * size_t(stride_),
        1.0 / grid_.cell_volume(), [&](size_t j, Rng& rng, PhotonBatch& batch) { beam.trace(j, rng, batch); },
        &rejection_failures_);
  }
  finish_tallies(&values_, grid_, ctx.media, channels_, blocks, smoothing);
}

bool BeamGrid::lookup(size_t light, const Vec3& p, const Rgb& T_light, const Rgb& T_wide, Rgb* factor,
                      Rgb* mean_cosine, Rgb* peak_toward, Rgb* wide_ratio) const {
  if (light >= values_.size() || values_[light].empty() || !grid_.bounds.contains(p)) return false;
  return lookup(light, p, grid_.stencil(p), T_light, T_wide, factor, mean_cosine, peak_toward, wide_ratio);
}

bool BeamGrid::lookup(size_t light, const Vec3& p, const TrilinearStencil& st, const Rgb& T_light,
                      const Rgb& T_wide, Rgb* factor, Rgb* mean_cosine, Rgb* peak_toward,
                      Rgb* wide_ratio) const {
  if (light >= values_.size() || values_[light].empty() || !grid_.bounds.contains(p)) return false;
  const FloatArray& v = values_[light];
  const int n = channels_;
  const Blocks blocks{.spread = spread_, .pk = with_camera_, .wide = with_wide_};
  const bool spread = spread_ && mean_cosine, pk_wanted = with_camera_ && peak_toward;
  const bool wide_wanted = with_wide_ && wide_ratio;
  Rgb r(0.0), straight(0.0), sp(0.0), sp_s(0.0), pk(0.0), pw(0.0), pm(0.0), r_plain(0.0), s_plain(0.0);
  for (int k = 0; k < 8; ++k)
    for (int c = 0; c < n; ++c) {
      const float* node = &v[st.node[k] * size_t(stride_) + c];
      r[c] += st.weight[k] * node[0];
      straight[c] += st.weight[k] * node[n];
      r_plain[c] += st.weight[k] * node[blocks.plain_block() * n];
      s_plain[c] += st.weight[k] * node[(blocks.plain_block() + 1) * n];
      if (spread) {
        sp[c] += st.weight[k] * node[2 * n];
        sp_s[c] += st.weight[k] * node[3 * n];
      }
      if (pk_wanted) pk[c] += st.weight[k] * node[blocks.pk_block() * n];
      if (wide_wanted) {
        pw[c] += st.weight[k] * node[blocks.wide_block() * n];
        pm[c] += st.weight[k] * node[(blocks.wide_block() + 1) * n];
      }
    }
  // The straight model's spread at p itself: the control variate of the tallies' spread (eq. D9b).
  const Rgb model =
      mean_cosine ? Rgb(1.0) - straight_mean_cosine(T_light, T_wide, one_minus_chi1_) : Rgb(0.0);
  for (int c = 0; c < n; ++c) {
    (*factor)[c] = straight[c] > 0.0 ? r[c] / straight[c] : 1.0;
    // At most the ratio of the plain tallies: R is a mean of traced / straight over the nodes' deposits, and
    // where the straight model's T_wide falls by orders of magnitude within a cell (a dense cloud's shadow
    // edges) its darkest samples would set R for the whole cell; T_wide R then lit the cell's brighter parts
    // with more light than its photons carried there.
    if (s_plain[c] > 0.0) (*factor)[c] = std::min((*factor)[c], r_plain[c] / s_plain[c]);
    if (mean_cosine) {
      double s = model[c];
      if (spread && r[c] > 0.0)
        s = sp[c] / r[c] + (straight[c] > 0.0 ? model[c] - sp_s[c] / straight[c] : 0.0);
      (*mean_cosine)[c] = 1.0 - std::clamp(s, 0.0, 2.0);
    }
    if (peak_toward) (*peak_toward)[c] = r[c] > 0.0 ? pk[c] / r[c] : 0.0;
    if (wide_ratio) (*wide_ratio)[c] = wide_wanted && pw[c] > 0.0 && pm[c] > 0.0 ? pw[c] / pm[c] : 1.0;
  }
  if (n == 1) {  // channel 0 stands for all three
    *factor = Rgb((*factor)[0]);
    if (mean_cosine) *mean_cosine = Rgb((*mean_cosine)[0]);
    if (peak_toward) *peak_toward = Rgb((*peak_toward)[0]);
    if (wide_ratio) *wide_ratio = Rgb((*wide_ratio)[0]);
  }
  return true;
}

size_t BeamGrid::memory_bytes() const {
  size_t bytes = 0;
  for (const auto& v : values_) bytes += v.size() * sizeof(float);
  return bytes;
}

}  // namespace nimbus
