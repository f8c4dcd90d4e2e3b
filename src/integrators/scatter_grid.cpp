#include "integrators/scatter_grid.h"

#include <tbb/parallel_for.h>

#include <cmath>

#include "core/sh.h"
#include "core/trilinear.h"
#include "integrators/shadow_map.h"
#include "integrators/tracking.h"

namespace nimbus {
namespace {

constexpr int kBatches = 8;
constexpr int kFloats = 9;  // BeamGrid, per node: traced (rgb), traced x mean cosine (rgb), straight (rgb)             // fixed: the grid must not depend on the thread count
constexpr int kMaxWideScatters = 1024;  // photons are ended after this many wide scatters ...
constexpr int kMaxEvents = 1 << 14;     // ... or real collisions
// Work budget: a batch stops starting photons once its collisions exceed this many per photon of the
// batch, and its deposits are scaled by planned / traced photons (optically very thick media would
// otherwise take hours; below the budget nothing changes).
constexpr double kEventsPerPhoton = 512.0;
struct Photon {
  Vec3 x, w;
  Rgb power;
};

// A photon leaving the light `source` (lights first, then the environment) towards the media's
// bounding sphere (centre c, radius r); power per photon for n photons of that source.
// strat: if given, the 2-D sample that places the photon (the disc point, or a point light's direction).
Photon emit(const SceneContext& ctx, size_t source, const Vec3& c, double r, double n, Rng& rng,
            const double* strat = nullptr) {
  double u1 = rng.uniform(), u2 = rng.uniform(), u3 = rng.uniform(), u4 = rng.uniform();
  if (strat) u1 = u3 = strat[0], u2 = u4 = strat[1];
  const double disc_area = kPi * r * r;
  auto through_disc = [&](const Vec3& w) {
    const Frame frame(w);
    const double rr = r * std::sqrt(u3), phi = 2.0 * kPi * u4;
    return c - w * (2.0 * r) + frame.to_world({rr * std::cos(phi), rr * std::sin(phi), 0.0});
  };
  Photon p;
  if (source < ctx.lights.size()) {
    const Light& light = ctx.lights[source];
    if (const auto* d = std::get_if<DirectionalLight>(&light)) {
      p.w = normalize(d->direction);
      p.x = through_disc(p.w);
      p.power = d->irradiance * (disc_area / n);
    } else if (const auto* pt = std::get_if<PointLight>(&light)) {
      const Vec3 v = c - pt->position;
      const double dist = v.length();
      p.x = pt->position;
      if (dist > r) {
        const double cos_max = std::sqrt(std::max(0.0, 1.0 - r * r / (dist * dist)));
        p.w = spherical_direction(1.0 - u1 * (1.0 - cos_max), 2.0 * kPi * u2, v / dist);
        p.power = pt->intensity * (2.0 * kPi * (1.0 - cos_max) / n);
      } else {
        p.w = spherical_direction(1.0 - 2.0 * u1, 2.0 * kPi * u2, Vec3(0, 0, 1));
        p.power = pt->intensity * (4.0 * kPi / n);
      }
    }
  } else {
    // Uniform radiance L from every direction: flux L 4 pi A through a disc of area A.
    p.w = spherical_direction(1.0 - 2.0 * u1, 2.0 * kPi * u2, Vec3(0, 0, 1));
    p.x = through_disc(p.w);
    p.power = ctx.environment * (4.0 * kPi * disc_area / n);
  }
  return p;
}

// Nodes covering the media's bounds, plus one spacing of padding on each side so every point of the
// media has a node's full support around it; `resolution` nodes along the longest axis.
void layout_nodes(const Bounds& media_bounds, int resolution, Bounds* bounds, std::array<int, 3>* nodes,
                  Vec3* spacing) {
  const Vec3 extent = media_bounds.hi - media_bounds.lo;
  const double longest = std::max({extent.x, extent.y, extent.z});
  for (int a = 0; a < 3; ++a) {
    const int inner = std::max(2, int(std::ceil(extent[a] / longest * (resolution - 1))) + 1);
    (*spacing)[a] = std::max(extent[a], 1e-6 * longest) / (inner - 1);
    (*nodes)[a] = inner + 2;
    bounds->lo[a] = media_bounds.lo[a] - (*spacing)[a];
    bounds->hi[a] = bounds->lo[a] + (*spacing)[a] * ((*nodes)[a] - 1);
  }
}

bool grey_media(const SceneContext& ctx) {
  bool grey = true;
  for (int i = 0; i < ctx.media.count(); ++i) {
    const Medium& m = ctx.media.medium(i);
    grey = grey && m.sigma_s.x == m.sigma_s.y && m.sigma_s.y == m.sigma_s.z && m.sigma_a.x == m.sigma_a.y &&
           m.sigma_a.y == m.sigma_a.z;
  }
  return grey;
}

}  // namespace

ScatterGrid::ScatterGrid(const SceneContext& ctx, const std::vector<const PhaseSplit*>& splits,
                         const std::vector<double>& peak_fraction, const ScatterGridSettings& s)
    : bands_(std::clamp(s.bands, 1, kShMaxBands)), coeffs_(bands_ * bands_) {
  const int kCoeffs = coeffs_, kFloatsPerNode = 3 * coeffs_;
  const Bounds media_bounds = ctx.media.bounds();
  if (media_bounds.empty()) {
    bounds_.lo = Vec3(0.0);
    bounds_.hi = Vec3(1.0);
    values_.assign(size_t(8) * 3 * coeffs_, 0.0f);
    return;
  }
  const Vec3 extent = media_bounds.hi - media_bounds.lo;
  layout_nodes(media_bounds, s.resolution > 0 ? s.resolution : 32, &bounds_, &nodes_, &spacing_);
  const size_t node_count = size_t(nodes_[0]) * nodes_[1] * nodes_[2];
  values_.assign(node_count * 3 * coeffs_, 0.0f);
  // With K = 1 only the environment's unscattered-by-wide light is needed (see the header).
  if (s.max_wide_scatters == 1 && !ctx.has_environment) return;

  // Grey media (every coefficient equal in all channels) take one pass carrying RGB power; otherwise
  // one pass per channel with that channel's coefficients.
  const bool grey = grey_media(ctx);
  const int passes = grey ? 1 : 3;
  const size_t lights = s.max_wide_scatters == 1 ? 0 : ctx.lights.size();  // K = 1: environment only
  const size_t sources = lights + (ctx.has_environment ? 1 : 0);
  if (sources == 0 || s.photons <= 0) return;
  const size_t per_source = std::max<size_t>(1, size_t(s.photons) / sources);
  const size_t total = size_t(passes) * sources * per_source;

  const Vec3 centre = (media_bounds.lo + media_bounds.hi) * 0.5;
  const double radius = 0.5 * extent.length() * (1.0 + 1e-9) + 1e-12;
  const double h_min = std::min({spacing_.x, spacing_.y, spacing_.z});
  const int K = s.max_wide_scatters <= 0 ? kMaxWideScatters : std::min(s.max_wide_scatters, kMaxWideScatters);
  const int media_count = ctx.media.count();

  std::vector<std::vector<float>> batch(kBatches);
  std::vector<double> batch_scale(kBatches, 1.0);
  tbb::parallel_for(0, kBatches, [&](int b) {
    std::vector<float>& g = batch[b];
    g.assign(node_count * kFloatsPerNode, 0.0f);
    // Splat value `v` (per channel; only channels with a non-zero entry) times the harmonics y at q.
    auto splat = [&](const Vec3& q, const double* y, const Rgb& v) {
      const TrilinearStencil st = trilinear_stencil(q, bounds_.lo, spacing_, nodes_);
      for (int k = 0; k < 8; ++k) {
        const double wt = st.weight[k];
        if (wt <= 0.0) continue;
        float* node = &g[st.node[k] * kFloatsPerNode];
        for (int c = 0; c < 3; ++c) {
          if (v[c] == 0.0) continue;
          const double e = wt * v[c];
          for (int h = 0; h < kCoeffs; ++h) node[kCoeffs * c + h] += float(e * y[h]);
        }
      }
    };
    // Track-length deposit of the flight x + t w, t in [0, t_end] (clipped to the node grid).
    auto deposit = [&](const Vec3& x, const Vec3& w, double t_end, const Rgb& power) {
      double t0, t1;
      if (!bounds_.intersect(x, w, 0.0, t_end, &t0, &t1)) return;
      const double len = t1 - t0;
      if (!(len > 0.0)) return;
      const int n = std::max(1, int(std::ceil(len / (0.5 * h_min))));
      const Rgb v = power * (len / n);
      double y[kShMaxBands * kShMaxBands];
      sh_eval(w, bands_, y);
      for (int k = 0; k < n; ++k) splat(x + w * (t0 + (k + 0.5) * len / n), y, v);
    };

    const size_t begin = total * size_t(b) / kBatches, end = total * size_t(b + 1) / kBatches;
    MediumPoint mp;
    const double budget = kEventsPerPhoton * double(end - begin);
    double spent = 0.0;
    size_t j = begin;
    for (; j < end && spent <= budget; ++j) {
      Rng rng(s.seed ^ 0x6d756c7469706c65ull, j);
      const int pass = int(j / (sources * per_source));
      size_t source = (j / per_source) % sources;
      if (source >= lights) source = ctx.lights.size();  // the environment
      // The environment's light is smooth in angle: the grid carries it from its entry (order 0).
      const int first_order = source < ctx.lights.size() ? 1 : 0;
      const int c = pass;  // the channel whose coefficients drive this photon
      Photon ph = emit(ctx, source, centre, radius, double(per_source), rng);
      Rgb power = ph.power;
      if (!grey)
        for (int k = 0; k < 3; ++k)
          if (k != c) power[k] = 0.0;
      if (max_component(power) <= 0.0) continue;
      Vec3 x = ph.x, w = ph.w;
      double weight = 1.0;
      int order = 0;  // wide scatters so far
      for (int events = 0; events < kMaxEvents; ++events, spent += 1.0) {
        bool hit = false;
        Vec3 xc;
        track(ctx.majorants, x, w, std::numeric_limits<double>::infinity(), rng,
              [&](const Vec3& p, double maj) {
                const double sigma = s.exact_transport ? ctx.media.sigma_t(p)[c]
                                                       : reduced_sigma_t(ctx.media, p, peak_fraction)[c];
                if (rng.uniform() * maj < sigma) {
                  hit = true;
                  xc = p;
                  return false;
                }
                return true;
              });
        if (order >= first_order)
          deposit(x, w, hit ? (xc - x).length() : std::numeric_limits<double>::infinity(), power * weight);
        if (!hit) break;
        // A real collision at xc: albedo weight, roulette, medium, direction.
        ctx.media.eval(xc, &mp);
        double part[kMaxMedia], part_sum = 0.0;
        for (int i = 0; i < mp.count && i < media_count; ++i) {
          part[i] = (s.exact_transport ? 1.0 : 1.0 - peak_fraction[i]) * mp.sigma_s_i[i][c];
          part_sum += part[i];
        }
        const double sigma = mp.sigma_a[c] + part_sum;
        if (!(part_sum > 0.0) || !(sigma > 0.0)) break;
        weight *= part_sum / sigma;
        if (weight < 0.1) {
          if (rng.uniform() * 0.1 >= weight) break;
          weight = 0.1;
        }
        double u = rng.uniform() * part_sum;
        int m = 0;
        while (m + 1 < mp.count && u >= part[m]) u -= part[m++];
        const Phase& phase = ctx.media.phase(m);
        const double f = peak_fraction[m];
        // The probability that a scatter into direction cosine mu is a wide one: (1 - f) P_wide / P.
        auto wide_share = [&](double mu) {
          const double p_full = phase_eval(phase, mu);
          return p_full > 0.0 ? (1.0 - f) * splits[m]->wide(mu) / p_full : 1.0;
        };
        if (s.exact_transport) {
          // The full phase function; the scatter counts as wide with its share.
          const double v1 = rng.uniform(), v2 = rng.uniform();
          const Vec3 w_new = phase_sample(phase, w, v1, v2);
          if (rng.uniform() < wide_share(dot(w_new, w)) && ++order >= K) break;
          w = w_new;
        } else {
          // Peak scatters are not events: draw P_wide by rejection from P (expected 1 / (1 - f) tries).
          if (++order >= K) break;
          for (int tries = 0; tries < 10000; ++tries) {
            const double v1 = rng.uniform(), v2 = rng.uniform();
            const Vec3 cand = phase_sample(phase, w, v1, v2);
            if (rng.uniform() < wide_share(dot(cand, w))) {
              w = cand;
              break;
            }
          }
        }
        x = xc;
      }
    }
    batch_scale[b] = j > begin ? double(end - begin) / double(j - begin) : 1.0;
  });

  // Sum the batches in order, divide by the node volume: fluence and flux.
  const double inv_volume = 1.0 / (spacing_.x * spacing_.y * spacing_.z);
  tbb::parallel_for(size_t(0), node_count, [&](size_t n) {
    for (int k = 0; k < kFloatsPerNode; ++k) {
      double sum = 0.0;
      for (int b = 0; b < kBatches; ++b) sum += batch_scale[b] * batch[b][n * kFloatsPerNode + k];
      values_[n * kFloatsPerNode + k] = float(sum * inv_volume);
    }
  });
  build_mips();
}

void ScatterGrid::build_mips() {
  // Each level halves the node count along every axis (nodes 2j of the level below), with the tent
  // filter (1/4, 1/2, 1/4) per axis; nodes beyond the level below's last are clamped to it.
  const int floats = 3 * coeffs_;
  const float* src = values_.data();
  std::array<int, 3> n = nodes_;
  Vec3 h = spacing_;
  while (std::max({n[0], n[1], n[2]}) > 4 && mips_.size() < 4) {
    Level lv;
    for (int a = 0; a < 3; ++a) {
      lv.nodes[a] = std::max(2, (n[a] + 2) / 2);
      lv.spacing[a] = 2.0 * h[a];
    }
    lv.values.assign(size_t(lv.nodes[0]) * lv.nodes[1] * lv.nodes[2] * floats, 0.0f);
    const std::array<int, 3> nb = n;
    auto at = [&](int x, int y, int z) {
      x = std::clamp(x, 0, nb[0] - 1), y = std::clamp(y, 0, nb[1] - 1), z = std::clamp(z, 0, nb[2] - 1);
      return src + ((size_t(z) * nb[1] + y) * nb[0] + x) * floats;
    };
    tbb::parallel_for(0, lv.nodes[2], [&](int z) {
      for (int y = 0; y < lv.nodes[1]; ++y)
        for (int x = 0; x < lv.nodes[0]; ++x) {
          float* out = &lv.values[((size_t(z) * lv.nodes[1] + y) * lv.nodes[0] + x) * floats];
          for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
              for (int dx = -1; dx <= 1; ++dx) {
                const double w = (dx ? 0.25 : 0.5) * (dy ? 0.25 : 0.5) * (dz ? 0.25 : 0.5);
                const float* in = at(2 * x + dx, 2 * y + dy, 2 * z + dz);
                for (int k = 0; k < floats; ++k) out[k] += float(w * in[k]);
              }
        }
    });
    mips_.push_back(std::move(lv));
    src = mips_.back().values.data();
    n = mips_.back().nodes;
    h = mips_.back().spacing;
  }
}

void ScatterGrid::accumulate(int level, const Vec3& p, double wt, double* L) const {
  const int floats = 3 * coeffs_;
  const Level* lv = level > 0 ? &mips_[level - 1] : nullptr;
  const TrilinearStencil st = trilinear_stencil(p, bounds_.lo, lv ? lv->spacing : spacing_, lv ? lv->nodes : nodes_);
  const float* v = lv ? lv->values.data() : values_.data();
  for (int k = 0; k < 8; ++k) {
    const float* node = &v[st.node[k] * floats];
    const double w = wt * st.weight[k];
    for (int h = 0; h < floats; ++h) L[h] += w * node[h];
  }
}

Rgb ScatterGrid::evaluate(const double* L, const Vec3& w_out, const std::array<Rgb, kShMaxBands>& chi) const {
  double y[kShMaxBands * kShMaxBands];
  sh_eval(w_out, bands_, y);
  Rgb r;
  for (int c = 0; c < 3; ++c) {
    double v = 0.0;
    for (int l = 0; l < bands_; ++l)
      for (int h = l * l; h < (l + 1) * (l + 1); ++h) v += chi[l][c] * L[coeffs_ * c + h] * y[h];
    r[c] = std::max(0.0, v);
  }
  return r;
}

Rgb ScatterGrid::scattered_filtered(const Vec3& p, const Vec3& w_out, const std::array<Rgb, kShMaxBands>& chi,
                                    double spread) const {
  if (!bounds_.contains(p)) return Rgb(0.0);
  const double h = std::min({spacing_.x, spacing_.y, spacing_.z});
  const double level = std::clamp(std::log2(std::max(spread, 1e-300) / h), 0.0, double(mips_.size()));
  if (!(level > 0.0)) return scattered(p, w_out, chi);
  double L[3 * kShMaxBands * kShMaxBands] = {};
  const int k0 = std::min(int(level), int(mips_.size()));
  const double f = level - k0;
  accumulate(k0, p, 1.0 - f, L);
  if (f > 0.0) accumulate(k0 + 1, p, f, L);
  return evaluate(L, w_out, chi);
}

Rgb ScatterGrid::scattered(const Vec3& p, const Vec3& w_out, const std::array<Rgb, kShMaxBands>& chi) const {
  if (!bounds_.contains(p)) return Rgb(0.0);
  double L[3 * kShMaxBands * kShMaxBands] = {};
  accumulate(0, p, 1.0, L);
  return evaluate(L, w_out, chi);
}

BeamGrid::BeamGrid(const SceneContext& ctx, const std::vector<const PhaseSplit*>& splits,
                   const std::vector<double>& peak_fraction, const std::vector<TransmittanceGrid>& reduced_maps,
                   int photons, int resolution, uint64_t seed) {
  values_.resize(ctx.lights.size());
  const Bounds media_bounds = ctx.media.bounds();
  if (media_bounds.empty() || photons <= 0 || reduced_maps.size() != ctx.lights.size()) return;
  layout_nodes(media_bounds, resolution, &bounds_, &nodes_, &spacing_);
  const size_t node_count = size_t(nodes_[0]) * nodes_[1] * nodes_[2];
  const bool grey = grey_media(ctx);
  const int passes = grey ? 1 : 3;
  const size_t per_light = size_t(photons);
  const Vec3 centre = (media_bounds.lo + media_bounds.hi) * 0.5;
  // Photons cover the whole node grid (its padding included), so every node's estimate is complete.
  const double radius = 0.5 * (bounds_.hi - bounds_.lo).length() * (1.0 + 1e-9) + 1e-12;
  const double h_min = std::min({spacing_.x, spacing_.y, spacing_.z});
  const int media_count = ctx.media.count();
  constexpr double kR2a1 = 0.75487766624669276, kR2a2 = 0.56984029099805327;  // the R2 sequence
  constexpr double kRoulette = 0.05;  // roulette below this ratio of weight to T_wide

  for (size_t l = 0; l < ctx.lights.size(); ++l) {
    const Light& light = ctx.lights[l];
    const auto* dir = std::get_if<DirectionalLight>(&light);
    const auto* point = std::get_if<PointLight>(&light);
    if (!dir && !point) continue;
    const Rgb strength = dir ? dir->irradiance : point->intensity;  // phi_0 = strength (/ r^2)
    const Vec3 dir_w = dir ? normalize(dir->direction) : Vec3(0.0);
    const TransmittanceGrid& T_wide = reduced_maps[l];
    const size_t total = size_t(passes) * per_light;
    std::vector<std::vector<float>> batch(kBatches);
    std::vector<double> batch_scale(kBatches, 1.0);
    tbb::parallel_for(0, kBatches, [&](int b) {
      std::vector<float>& g = batch[b];
      g.assign(node_count * kFloats, 0.0f);
      // Track-length deposit of the flight x + t w, t in [0, t_end] (clipped to the grid), starting with
      // `weight` (channel c only unless grey) and losing exp(-int sigma_loss) along the way (midpoint
      // rule at the deposit samples); each sample divided by the straight-line model at that point.
      // Returns the weight at t_end.
      auto deposit = [&](const Vec3& x, const Vec3& w, double t_end, Rgb weight, int c, bool straight) -> Rgb {
        double t0, t1;
        if (!bounds_.intersect(x, w, 0.0, t_end, &t0, &t1) || !(t1 - t0 > 0.0)) return weight;
        const double len = t1 - t0;
        const int n = std::max(1, int(std::ceil(len / (0.25 * h_min))));
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
          const TrilinearStencil st = trilinear_stencil(q, bounds_.lo, spacing_, nodes_);
          for (int ch = 0; ch < 3; ++ch) {
            if ((!grey && ch != c) || !(tw[ch] > 1e-30)) continue;
            const double v = mid[ch] * dl / (tw[ch] * geo);
            for (int j = 0; j < 8; ++j)
              if (st.weight[j] > 0.0) {
                float* node = &g[st.node[j] * kFloats];
                if (straight) {
                  node[6 + ch] += float(st.weight[j] * v);
                } else {
                  node[ch] += float(st.weight[j] * v);
                  node[3 + ch] += float(st.weight[j] * v * mu);
                }
              }
          }
        }
        return weight;
      };
      const size_t begin = total * size_t(b) / kBatches, end = total * size_t(b + 1) / kBatches;
      MediumPoint mp;
      const double budget = kEventsPerPhoton * double(end - begin);
      double spent = 0.0;
      size_t j = begin;
      for (; j < end && spent <= budget; ++j) {
        Rng rng(seed ^ 0x7065616b6265616dull ^ (uint64_t(l) << 40), j);
        const int c = int(j / per_light);
        const size_t k = j % per_light;
        double strat[2] = {0.5 + k * kR2a1, 0.5 + k * kR2a2};
        for (double& u : strat) u -= std::floor(u);
        const Photon ph = emit(ctx, l, centre, radius, double(per_light), rng, strat);
        // Power per photon over phi_0's strength: the geometry of the emission only.
        Rgb weight(0.0);
        for (int ch = 0; ch < 3; ++ch)
          if ((grey || ch == c) && strength[ch] > 0.0) weight[ch] = ph.power[ch] / strength[ch];
        if (max_component(weight) <= 0.0) continue;
        const double w0 = weight[c];
        Vec3 x = ph.x, w = ph.w;
        // The same photon undeflected: the straight-line model with the same emission (a control
        // variate: R = traced / straight cancels the emission's sampling noise).
        deposit(x, w, std::numeric_limits<double>::infinity(), weight, c, true);
        for (int events = 0; events < kMaxEvents; ++events, spent += 1.0) {
          // Flights end at peak scatters only (rate sum_m f_m sigma_s,m); absorption and wide scatters
          // are the continuous loss exp(-int sigma_loss) on the weight (zero variance in a uniform medium).
          bool hit = false;
          Vec3 xc;
          track(ctx.majorants, x, w, std::numeric_limits<double>::infinity(), rng, [&](const Vec3& p, double maj) {
            ctx.media.eval(p, &mp);
            double peak = 0.0;
            for (int i = 0; i < mp.count && i < media_count; ++i) peak += peak_fraction[i] * mp.sigma_s_i[i][c];
            if (rng.uniform() * maj < peak) {
              hit = true;
              xc = p;
              return false;
            }
            return true;
          });
          weight = deposit(x, w, hit ? (xc - x).length() : std::numeric_limits<double>::infinity(), weight, c, false);
          if (!hit) break;
          // Roulette on the ratio to the model (what is deposited), not on the weight alone.
          const double tw = T_wide.lookup(xc)[c] * w0;
          if (tw > 0.0 && weight[c] < kRoulette * tw) {
            const double keep = weight[c] / (kRoulette * tw);
            if (rng.uniform() >= keep) break;
            weight *= 1.0 / keep;
          }
          ctx.media.eval(xc, &mp);
          double part[kMaxMedia], part_sum = 0.0;
          for (int i = 0; i < mp.count && i < media_count; ++i) {
            part[i] = peak_fraction[i] * mp.sigma_s_i[i][c];
            part_sum += part[i];
          }
          if (!(part_sum > 0.0)) break;
          double u = rng.uniform() * part_sum;
          int m = 0;
          while (m + 1 < mp.count && u >= part[m]) u -= part[m++];
          const Phase& phase = ctx.media.phase(m);
          const double f = peak_fraction[m];
          // P_peak by rejection from P: accept with f P_peak / P (expected 1 / f tries).
          for (int tries = 0; tries < 10000; ++tries) {
            const Vec3 cand = phase_sample(phase, w, rng.uniform(), rng.uniform());
            const double mu = dot(cand, w), p_full = phase_eval(phase, mu);
            if (p_full > 0.0 && rng.uniform() * p_full < f * splits[m]->peak(mu)) {
              w = cand;
              break;
            }
          }
          x = xc;
        }
      }
      batch_scale[b] = j > begin ? double(end - begin) / double(j - begin) : 1.0;
    });
    const double inv_volume = 1.0 / (spacing_.x * spacing_.y * spacing_.z);
    std::vector<float>& out = values_[l];
    out.assign(node_count * kFloats, 0.0f);
    tbb::parallel_for(size_t(0), node_count * kFloats, [&](size_t n) {
      double sum = 0.0;
      for (int b = 0; b < kBatches; ++b) sum += batch_scale[b] * batch[b][n];
      out[n] = float(sum * inv_volume);
    });
  }
}

bool BeamGrid::lookup(size_t light, const Vec3& p, Rgb* factor, Rgb* mean_cosine) const {
  if (light >= values_.size() || values_[light].empty() || !bounds_.contains(p)) return false;
  const std::vector<float>& v = values_[light];
  const TrilinearStencil st = trilinear_stencil(p, bounds_.lo, spacing_, nodes_);
  Rgb r(0.0), m(0.0), straight(0.0);
  for (int k = 0; k < 8; ++k)
    for (int c = 0; c < 3; ++c) {
      r[c] += st.weight[k] * v[st.node[k] * kFloats + c];
      m[c] += st.weight[k] * v[st.node[k] * kFloats + 3 + c];
      straight[c] += st.weight[k] * v[st.node[k] * kFloats + 6 + c];
    }
  for (int c = 0; c < 3; ++c) {
    (*factor)[c] = straight[c] > 0.0 ? r[c] / straight[c] : 1.0;
    (*mean_cosine)[c] = r[c] > 0.0 ? std::clamp(m[c] / r[c], -1.0, 1.0) : 1.0;
  }
  return true;
}

size_t BeamGrid::memory_bytes() const {
  size_t bytes = 0;
  for (const auto& v : values_) bytes += v.size() * sizeof(float);
  return bytes;
}

}  // namespace nimbus
