// The shadow maps (integrators/shadow_map.h): reduced extinction, marched transmittance, the node grid.
#include "integrators/shadow_map.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "integrators/tracking.h"
#include "scene/lights.h"

namespace nimbus {

Rgb reduced_sigma_t(const SceneMedia& media, const Vec3& p, const std::vector<double>& peak_fraction) {
  if (peak_fraction.empty()) return media.sigma_t(p);
  MediumPoint mp;
  media.eval(p, &mp);
  return reduced_sigma_t(mp, peak_fraction);
}

Rgb reduced_sigma_t(const MediumPoint& mp, const std::vector<double>& peak_fraction) {
  Rgb s = mp.sigma_t();
  for (int i = 0; i < mp.count && i < int(peak_fraction.size()); ++i) s -= mp.sigma_s_i[i] * peak_fraction[i];
  return s;
}

Rgb marched_transmittance(const SceneMedia& media, const MajorantGrid& grid, const Vec3& p, const Vec3& w,
                          double tmax, double tau_step, const std::vector<double>& peak_fraction) {
  Rgb tau(0.0);
  march(grid, p, w, tmax, tau_step, 0.5, [&](const Vec3& x, double, double dt) {
    tau += reduced_sigma_t(media, x, peak_fraction) * dt;
    return min_component(tau) < 50.0;
  });
  return exp_channels(-tau);  // grey maps: one exp
}

namespace {

// A map's sum stops after the step that takes every channel's optical depth to this (T ~ 2e-22).
constexpr double kTauStop = 50.0;

// The optical depths of the plain and the reduced extinction (peak_fraction) along p + t w, t in
// (0, tmax), by the midpoint march of tau_step. tau_in: each map's depth already between the segment's
// end and the light (0 for a whole march to the light); a sum is not taken (want false) or stops after
// the step that takes tau_in + tau to kTauStop in every channel.
void segment_depths(const SceneMedia& media, const MajorantGrid& grid,
                    const std::vector<double>& peak_fraction, const Vec3& p, const Vec3& w, double tmax,
                    double tau_step, bool want_full, const Rgb& tau_in_full, bool want_reduced,
                    const Rgb& tau_in_reduced, Rgb* tau_full, Rgb* tau_reduced) {
  *tau_full = *tau_reduced = Rgb(0.0);
  bool full_done = !want_full || min_component(tau_in_full) >= kTauStop;
  bool reduced_done = !want_reduced || min_component(tau_in_reduced) >= kTauStop;
  if (full_done && reduced_done) return;
  MediumPoint mp;
  march(grid, p, w, tmax, tau_step, 0.5, [&](const Vec3& x, double, double dt) {
    media.eval(x, &mp);
    Rgb s = mp.sigma_t();
    if (!full_done) {
      *tau_full += s * dt;
      full_done = min_component(*tau_full + tau_in_full) >= kTauStop;
    }
    if (!reduced_done) {
      for (int i = 0; i < mp.count && i < int(peak_fraction.size()); ++i)
        s -= mp.sigma_s_i[i] * peak_fraction[i];
      *tau_reduced += s * dt;
      reduced_done = min_component(*tau_reduced + tau_in_reduced) >= kTauStop;
    }
    return !(full_done && reduced_done);
  });
}

// A constant offset `d` (in node spacings) along one axis of a slice, split into whole nodes and a
// fraction in [0, 1) (snapped to a whole node within 1e-9: a light along a node diagonal), and the
// weights of the nodes whole - 1 ... whole + 2 around it: linear, or Catmull-Rom (cubic).
struct AxisOffset {
  int whole = 0;
  double frac = 0.0;
  double weight[4] = {0.0, 1.0, 0.0, 0.0};
  AxisOffset(double d, bool cubic) {
    const double f = std::floor(d);
    whole = int(f);
    frac = d - f;
    if (frac < 1e-9) frac = 0.0;
    if (frac > 1.0 - 1e-9) frac = 0.0, ++whole;
    const double t = frac, t2 = t * t, t3 = t2 * t;
    if (cubic) {
      weight[0] = 0.5 * (-t3 + 2.0 * t2 - t);
      weight[1] = 0.5 * (3.0 * t3 - 5.0 * t2 + 2.0);
      weight[2] = 0.5 * (-3.0 * t3 + 4.0 * t2 + t);
      weight[3] = 0.5 * (t3 - t2);
    } else {
      weight[1] = 1.0 - t;
      weight[2] = t;
    }
  }
  // Whether i + d lies within the nodes' span [0, n - 1] (else the point is outside the media's bounds).
  bool inside(int i, int n) const {
    const int j = i + whole;
    return j >= 0 && (j < n - 1 || (j == n - 1 && frac == 0.0));
  }
  // The node k in -1 ... 2 of the stencil around i + d, clamped into [0, n).
  int node(int i, int k, int n) const { return std::clamp(i + whole + k - 1, 0, n - 1); }
  // The interpolated value of v[0..3] (the stencil's nodes), kept within its two middle nodes' values (a
  // cubic's overshoot at a shadow's edge would otherwise grow slice after slice).
  Rgb interpolate(const Rgb v[4]) const {
    Rgb r = v[0] * weight[0] + v[1] * weight[1] + v[2] * weight[2] + v[3] * weight[3];
    for (int c = 0; c < 3; ++c)
      r[c] = std::clamp(r[c], std::min(v[1][c], v[2][c]), std::max(v[1][c], v[2][c]));
    return r;
  }
};

// The node values being filled: the full map and the reduced one (either may be null), the optical
// depth to the light per node, rgb (lookups interpolate it and exponentiate; see lookup).
struct MapValues {
  NodeGrid g;
  FloatArray* full;
  FloatArray* reduced;
  void store(size_t node, const Rgb& tau_full, const Rgb& tau_reduced) const {
    for (int c = 0; c < 3; ++c) {
      if (full) (*full)[node * 3 + c] = float(tau_full[c]);
      if (reduced) (*reduced)[node * 3 + c] = float(tau_reduced[c]);
    }
  }
};

// One march per node to the centre of the light (a sun disc is treated as its centre direction here; a
// spot's map covers its whole sphere of directions, the cone is applied by sample_light).
void march_every_node(const SceneMedia& media, const MajorantGrid& grid, const Light& light, double tau_step,
                      const std::vector<double>& peak_fraction, const MapValues& maps) {
  const NodeGrid& g = maps.g;
  tbb::parallel_for(0, g.nodes[2], [&](int z) {
    for (int y = 0; y < g.nodes[1]; ++y)
      for (int x = 0; x < g.nodes[0]; ++x) {
        const Vec3 p = g.position(x, y, z);
        Vec3 wi;
        double distance = 0.0;
        if (!light_centre(light, p, &wi, &distance)) continue;
        Rgb tau, tau_reduced;
        segment_depths(media, grid, peak_fraction, p, wi, distance, tau_step, maps.full, Rgb(0.0),
                       maps.reduced, Rgb(0.0), &tau, &tau_reduced);
        maps.store(g.index(x, y, z), tau, tau_reduced);
      }
  });
}

// The sweep (MapBuild) towards a directional light; w: towards the light (unit).
void sweep_towards(const SceneMedia& media, const MajorantGrid& grid, const Vec3& w, double tau_step,
                   const std::vector<double>& peak_fraction, const MapBuild& how, const MapValues& maps) {
  const NodeGrid& g = maps.g;
  // Axis a: the one along which the light advances the most node spacings per unit length, so a sweep
  // step of `stride` slices moves at most `stride` spacings across (b, c).
  int a = 0;
  for (int k = 1; k < 3; ++k)
    if (std::abs(w[k]) / g.spacing[k] > std::abs(w[a]) / g.spacing[a]) a = k;
  const int b = (a + 1) % 3, c = (a + 2) % 3, nb = g.nodes[b], nc = g.nodes[c];
  const int n = g.nodes[a], toward = w[a] > 0.0 ? 1 : -1;
  const int first = toward > 0 ? n - 1 : 0;  // the slice on the light's face: transmittance 1
  const auto index = [&](int ka, int kb, int kc) {
    std::array<int, 3> i;
    i[a] = ka, i[b] = kb, i[c] = kc;
    return g.index(i[0], i[1], i[2]);
  };
  for (int s = 1; s < n; ++s) {
    const int k = first - toward * s;                       // this slice
    const int span = std::min(std::max(1, how.stride), s);  // slices to the one it reads
    const int j = k + toward * span;                        // that slice, already done
    const double t_seg = span * g.spacing[a] / std::abs(w[a]);
    const AxisOffset off_b(w[b] * t_seg / g.spacing[b], how.cubic),
        off_c(w[c] * t_seg / g.spacing[c], how.cubic);
    // The optical depth in slice j where a node's segment of t_seg towards the light meets it (depth,
    // not transmittance: it is the smoother of the two, and a lerp of T errs by the convexity of exp).
    const auto in_slice = [&](const FloatArray& v, int kb, int kc) {
      Rgb column[4];
      for (int qc = 0; qc < 4; ++qc) {
        Rgb row[4];
        for (int qb = 0; qb < 4; ++qb) {
          const size_t i = index(j, off_b.node(kb, qb, nb), off_c.node(kc, qc, nc)) * 3;
          row[qb] = Rgb(v[i], v[i + 1], v[i + 2]);
        }
        column[qc] = off_b.interpolate(row);
      }
      return off_c.interpolate(column);
    };
    tbb::parallel_for(0, nc, [&](int kc) {
      for (int kb = 0; kb < nb; ++kb) {
        // 0 where the segment's end is outside the bounds: the ray does not come back in.
        Rgb in_full(0.0), in_reduced(0.0);
        if (off_b.inside(kb, nb) && off_c.inside(kc, nc)) {
          if (maps.full) in_full = in_slice(*maps.full, kb, kc);
          if (maps.reduced) in_reduced = in_slice(*maps.reduced, kb, kc);
        }
        std::array<int, 3> at;
        at[a] = k, at[b] = kb, at[c] = kc;
        Rgb tau, tau_reduced;
        segment_depths(media, grid, peak_fraction, g.position(at[0], at[1], at[2]), w, t_seg, tau_step,
                       maps.full, in_full, maps.reduced, in_reduced, &tau, &tau_reduced);
        maps.store(index(k, kb, kc), in_full + tau, in_reduced + tau_reduced);
      }
    });
  }
}

}  // namespace

void TransmittanceGrid::build(const SceneMedia& media, const MajorantGrid& grid, const Light& light,
                              int resolution, double tau_step, const std::vector<double>& peak_fraction,
                              TransmittanceGrid* full, TransmittanceGrid* reduced, MapBuild how) {
  Bounds bounds = grid.bounds();
  if (bounds.empty()) {
    bounds.lo = Vec3(0.0);
    bounds.hi = Vec3(1.0);
  }
  const NodeGrid g = node_grid_spanning(bounds, resolution);
  for (TransmittanceGrid* m : {full, reduced})
    if (m) m->grid_ = g, m->values_.assign(g.size() * 3, 0.0f);
  const MapValues maps{g, full ? &full->values_ : nullptr, reduced ? &reduced->values_ : nullptr};
  if (const auto* sun = std::get_if<DirectionalLight>(&light); sun && how.sweep)
    sweep_towards(media, grid, -sun->direction, tau_step, peak_fraction, how, maps);
  else
    march_every_node(media, grid, light, tau_step, peak_fraction, maps);
}

TransmittanceGrid::TransmittanceGrid(const SceneMedia& media, const MajorantGrid& grid, const Light& light,
                                     int resolution, double tau_step,
                                     const std::vector<double>& peak_fraction, MapBuild how) {
  // The reduced extinction's sum is taken with peak_fraction, the plain one without.
  if (peak_fraction.empty())
    build(media, grid, light, resolution, tau_step, peak_fraction, this, nullptr, how);
  else
    build(media, grid, light, resolution, tau_step, peak_fraction, nullptr, this, how);
}

void TransmittanceGrid::build_pair(const SceneMedia& media, const MajorantGrid& grid, const Light& light,
                                   int resolution, double tau_step, const std::vector<double>& peak_fraction,
                                   TransmittanceGrid* full, TransmittanceGrid* reduced, MapBuild how) {
  build(media, grid, light, resolution, tau_step, peak_fraction, full, reduced, how);
}

Rgb TransmittanceGrid::lookup(const Vec3& p) const { return lookup(grid_.stencil(p)); }

Rgb TransmittanceGrid::lookup(const TrilinearStencil& st) const {
  // Interpolated in optical depth, not in transmittance: exp is convex, so a lerp of T between a node
  // the light reaches and one deep in shadow is too bright (by up to ~50 % where the light grazes a dense
  // medium's boundary, the backlit spheres' rim; docs/validation/render.md), while the depth along the
  // light's path varies smoothly.
  if (values_.empty()) return Rgb(0.0);
  Rgb tau(0.0);
  for (int k = 0; k < 8; ++k) {
    const float* v = &values_[st.node[k] * 3];
    tau += Rgb(v[0], v[1], v[2]) * st.weight[k];
  }
  return exp_channels(-tau);  // grey maps: one exp
}

}  // namespace nimbus
