// Photon Monte Carlo of a pencil beam in a slab or an infinite medium (MCML conventions): the tracer,
// the tallies at planes and faces, and batch-mean error estimates (photon_mc.h).
#include "transport/photon_mc.h"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "core/rng.h"
#include "nimbus/error.h"

namespace nimbus {

double fresnel_reflectance(double n_i, double n_t, double cos_i, double* cos_t) {
  cos_i = std::min(std::abs(cos_i), 1.0);
  if (n_i == n_t) {
    if (cos_t) *cos_t = cos_i;
    return 0.0;
  }
  const double sin_i = std::sqrt(std::max(0.0, 1.0 - cos_i * cos_i));
  const double sin_t = n_i / n_t * sin_i;  // Snell
  if (sin_t >= 1.0) {                      // total internal reflection
    if (cos_t) *cos_t = 0.0;
    return 1.0;
  }
  const double ct = std::sqrt(1.0 - sin_t * sin_t);
  if (cos_t) *cos_t = ct;
  // Fresnel amplitudes for s and p polarisation; unpolarised light reflects their mean square.
  const double rs = (n_i * cos_i - n_t * ct) / (n_i * cos_i + n_t * ct);
  const double rp = (n_t * cos_i - n_i * ct) / (n_t * cos_i + n_i * ct);
  return 0.5 * (rs * rs + rp * rp);
}

namespace {

constexpr double kRouletteThreshold = 1e-4;  // MCML
constexpr double kRouletteSurvival = 0.1;    // MCML

// Offsets of every tally in one flat accumulator per batch.
// Time tallies take TS = NT + 2 slots (before the first edge, the NT bins, after the last; 0 without
// time bins), each plane 2 TS (all scattered forward crossings, and those of photons that never travelled
// backward) and MS = 6 more (delay moments: weight, weight * delay, weight * delay^2, of all
// scattered forward crossings and of those by photons that never travelled backward); the joint tallies
// JA = (NA + 1) TS and JR = (NR + 1) TS slots (the last angle or radius slot: outside the edges).
struct Layout {
  size_t P, NA, NR, TS = 0, MS = 0, JA = 0, JR = 0;
  size_t plane_stride() const { return 2 * NA + NR + 1 + 2 * TS + MS + JA + JR; }
  size_t angular(size_t k) const { return k * plane_stride(); }
  size_t radial(size_t k) const { return k * plane_stride() + NA; }
  size_t unscattered(size_t k) const { return k * plane_stride() + NA + NR; }
  size_t angular_forward_only(size_t k) const { return k * plane_stride() + NA + NR + 1; }
  size_t delay(size_t k) const { return k * plane_stride() + 2 * NA + NR + 1; }
  size_t delay_forward_only(size_t k) const { return delay(k) + TS; }
  size_t moments(size_t k) const { return delay(k) + 2 * TS; }
  size_t delay_angle(size_t k) const { return moments(k) + MS; }  // + angle slot * TS + time slot
  size_t delay_radius(size_t k) const { return delay_angle(k) + JA; }
  size_t totals() const { return P * plane_stride(); }  // specular, Rd, Tt, Tu, absorbed
  size_t reflect_angular() const { return totals() + 5; }
  size_t reflect_radial() const { return reflect_angular() + NA; }
  size_t transmit_angular() const { return reflect_radial() + NR; }
  size_t transmit_radial() const { return transmit_angular() + NA; }
  size_t reflect_time() const { return transmit_radial() + NR; }
  size_t transmit_time() const { return reflect_time() + TS; }
  size_t size() const { return transmit_time() + TS; }
};
enum Total { kSpecular = 0, kReflect = 1, kTransmit = 2, kUnscatteredT = 3, kAbsorbed = 4 };

// Index of the bin of `edges` that holds v, or -1 outside.
int bin_of(const std::vector<double>& edges, double v) {
  if (edges.size() < 2 || !(v >= edges.front()) || v >= edges.back()) return -1;
  return int(std::upper_bound(edges.begin(), edges.end(), v) - edges.begin()) - 1;
}

// Slot of time t among the TS time slots (0: before the first edge, TS - 1: at or after the last).
size_t time_slot(const std::vector<double>& edges, double t) {
  if (t < edges.front()) return 0;
  if (t >= edges.back()) return edges.size();
  return size_t(std::upper_bound(edges.begin(), edges.end(), t) - edges.begin());
}

void validate(const PhotonMcSettings& s) {
  auto bad = [](const std::string& m) { throw Error("photon mc: " + m); };
  if (!(s.sigma_s >= 0.0) || !std::isfinite(s.sigma_s)) bad("sigma_s must be finite and >= 0");
  if (!(s.sigma_a >= 0.0) || !std::isfinite(s.sigma_a)) bad("sigma_a must be finite and >= 0");
  if (!(s.thickness > 0.0)) bad("thickness must be > 0");
  if (std::isinf(s.thickness) && !(s.sigma_s + s.sigma_a > 0.0)) bad("an infinite medium needs sigma_t > 0");
  if (!(s.n > 0.0) || !std::isfinite(s.n)) bad("refractive index must be > 0");
  for (size_t i = 0; i < s.plane_depths.size(); ++i) {
    const double z = s.plane_depths[i];
    if (!(z > 0.0) || !(z < s.thickness)) bad(fmt::format("plane depth {} must lie in (0, thickness)", z));
    if (i > 0 && !(z > s.plane_depths[i - 1])) bad("plane depths must increase");
  }
  for (size_t i = 0; i < s.theta_edges.size(); ++i) {
    if (!(s.theta_edges[i] >= 0.0 && s.theta_edges[i] <= kPi + 1e-12)) bad("theta edges must lie in [0, pi]");
    if (i > 0 && !(s.theta_edges[i] > s.theta_edges[i - 1])) bad("theta edges must increase");
  }
  for (size_t i = 0; i < s.r_edges.size(); ++i) {
    if (!(s.r_edges[i] >= 0.0) || !std::isfinite(s.r_edges[i])) bad("radius edges must be finite and >= 0");
    if (i > 0 && !(s.r_edges[i] > s.r_edges[i - 1])) bad("radius edges must increase");
  }
  for (size_t i = 0; i < s.time_edges.size(); ++i) {
    if (!(s.time_edges[i] >= 0.0) || !std::isfinite(s.time_edges[i]))
      bad("time edges must be finite and >= 0");
    if (i > 0 && !(s.time_edges[i] > s.time_edges[i - 1])) bad("time edges must increase");
  }
  if (s.time_edges.size() == 1) bad("time edges need at least two values");
  // Every batch holds all tallies: refuse what would not fit in memory (1 GiB of tallies).
  if ((s.joint_angle || s.joint_radius) && s.time_edges.empty()) bad("joint tallies need time edges");
  const double joint = (s.joint_angle ? double(s.theta_edges.size() + 1) : 0.0) +
                       (s.joint_radius ? double(s.r_edges.size() + 1) : 0.0);
  const double slots = double(s.time_edges.size() + 4) * double(s.plane_depths.size() + 2) * (2.0 + joint) +
                       double(s.theta_edges.size() + s.r_edges.size()) * double(s.plane_depths.size() + 2);
  if (slots * double(s.batches) * sizeof(double) > double(1u << 30))
    bad(fmt::format("{} time bins at {} planes need more than 1 GiB of tallies", s.time_edges.size(),
                    s.plane_depths.size()));
  if (s.batches < 2) bad("needs at least 2 batches");
  if (s.photons < uint64_t(s.batches)) bad("needs at least one photon per batch");
}

// One photon history; adds its tallies to acc.
class Tracer {
 public:
  Tracer(const PhotonMcSettings& s, const Layout& L) : s_(s), L_(L) {
    sigma_t_ = s.sigma_s + s.sigma_a;
    slab_ = std::isfinite(s.thickness);
    const double g = std::clamp(phase_mean_cosine(s.phase), -1.0, 0.999);
    zone_len_ = 1.0 / (s.sigma_s * (1.0 - g) + s.sigma_a);  // transport length
    z_last_ = s.plane_depths.empty() ? 0.0 : s.plane_depths.back();
  }

  void trace(Rng& rng, double* acc) const {
    double w = 1.0;
    // Specular reflection at the entry face (normal incidence).
    if (slab_) {
      const double rsp = fresnel_reflectance(1.0, s_.n, 1.0);
      acc[L_.totals() + kSpecular] += rsp;
      w = 1.0 - rsp;
    }
    Vec3 p(0.0, 0.0, 0.0), d(0.0, 0.0, 1.0);
    bool scattered = false, turned = false;
    int zone_seen = 0;
    double path = 0.0;  // path length travelled in the medium
    const double inf = std::numeric_limits<double>::infinity();
    while (true) {
      // Free path, and the distance to the face ahead.
      const double s = sigma_t_ > 0.0 ? -std::log(1.0 - rng.uniform()) / sigma_t_ : inf;
      double s_face = inf;
      if (slab_) {
        if (d.z > 0.0)
          s_face = (s_.thickness - p.z) / d.z;
        else if (d.z < 0.0)
          s_face = -p.z / d.z;
      }
      const bool hits = s >= s_face;
      const double step = hits ? s_face : s;
      if (!std::isfinite(step)) return;  // moving parallel to the faces of an empty slab
      Vec3 p1 = p + d * step;
      if (hits) p1.z = d.z > 0.0 ? s_.thickness : 0.0;
      tally_planes(p, p1, d, path, w, scattered, turned, acc);
      p = p1;
      path += step;

      if (hits) {
        reflect_at_face(p, d, path, w, scattered, turned, acc);
        if (!(w > 0.0)) return;
      } else {
        interact(rng, d, w, scattered, turned, acc);
      }
      if (!survives_roulette(rng, p, w, zone_seen)) return;
    }
  }

 private:
  // Fresnel at the face: the transmitted part leaves (tallied), the reflected part goes on.
  void reflect_at_face(const Vec3& p, Vec3& d, double path, double& w, bool scattered, bool& turned,
                       double* acc) const {
    double cos_t = 0.0;
    const double R = fresnel_reflectance(s_.n, 1.0, d.z, &cos_t);
    const double wt = w * (1.0 - R);
    if (wt > 0.0)
      tally_exit(d.z > 0.0, std::acos(std::clamp(cos_t, 0.0, 1.0)), p, s_.n * path, wt, scattered, acc);
    w *= R;
    d.z = -d.z;
    turned = turned || d.z <= 0.0;
  }

  // Interaction: deposit the absorbed fraction, scatter the rest.
  void interact(Rng& rng, Vec3& d, double& w, bool& scattered, bool& turned, double* acc) const {
    const double dep = w * s_.sigma_a / sigma_t_;
    acc[L_.totals() + kAbsorbed] += dep;
    w -= dep;
    const double u1 = rng.uniform(), u2 = rng.uniform();
    d = normalize(phase_sample(s_.phase, d, u1, u2));
    scattered = true;
    turned = turned || d.z <= 0.0;
  }

  // Russian roulette on weight (MCML): survive with probability 0.1 at weight / 0.1. Infinite medium:
  // depth roulette too, halving the population per transport length beyond the tallies.
  bool survives_roulette(Rng& rng, const Vec3& p, double& w, int& zone_seen) const {
    if (w < kRouletteThreshold) {
      if (rng.uniform() < kRouletteSurvival)
        w /= kRouletteSurvival;
      else
        return false;
    }
    if (!slab_) {
      const double zone = std::max(std::floor((p.z - z_last_) / zone_len_), std::floor(-p.z / zone_len_));
      while (zone > zone_seen) {
        ++zone_seen;
        if (rng.uniform() < 0.5)
          w *= 2.0;
        else
          return false;
      }
    }
    return true;
  }

  // Crossings of the tally planes by the segment p0 -> p1 (direction d), which starts after `path`.
  void tally_planes(const Vec3& p0, const Vec3& p1, const Vec3& d, double path, double w, bool scattered,
                    bool turned, double* acc) const {
    const auto& zs = s_.plane_depths;
    if (zs.empty() || d.z == 0.0) return;
    size_t k0, k1;  // planes [k0, k1) are crossed
    if (d.z > 0.0) {
      k0 = size_t(std::upper_bound(zs.begin(), zs.end(), p0.z) - zs.begin());
      k1 = size_t(std::upper_bound(zs.begin(), zs.end(), p1.z) - zs.begin());
    } else {
      k0 = size_t(std::lower_bound(zs.begin(), zs.end(), p1.z) - zs.begin());
      k1 = size_t(std::lower_bound(zs.begin(), zs.end(), p0.z) - zs.begin());
    }
    for (size_t k = k0; k < k1; ++k) {
      if (!scattered) {
        acc[L_.unscattered(k)] += w;
        continue;
      }
      const int ia = bin_of(s_.theta_edges, std::acos(std::clamp(d.z, -1.0, 1.0)));
      if (ia >= 0) {
        acc[L_.angular(k) + ia] += w / std::abs(d.z);
        if (!turned) acc[L_.angular_forward_only(k) + ia] += w / std::abs(d.z);
      }
      if (d.z > 0.0) {
        const double t = (zs[k] - p0.z) / d.z;
        const int ir = bin_of(s_.r_edges, std::hypot(p0.x + d.x * t, p0.y + d.y * t));
        if (ir >= 0) acc[L_.radial(k) + ir] += w;
        // The delay is >= 0; rounding could push a nearly straight path a hair below.
        if (L_.TS > 0) tally_delay(k, std::max(0.0, s_.n * (path + t - zs[k])), w, turned, ia, ir, acc);
      }
    }
  }

  // A scattered forward crossing of plane k with delay n (s - z_k).
  // ia, ir: its angle and radius bins (-1 outside the edges), for the joint tallies.
  void tally_delay(size_t k, double delay, double w, bool turned, int ia, int ir, double* acc) const {
    const size_t ts = time_slot(s_.time_edges, delay);
    acc[L_.delay(k) + ts] += w;
    if (!turned) acc[L_.delay_forward_only(k) + ts] += w;
    if (L_.JA > 0) acc[L_.delay_angle(k) + (ia >= 0 ? size_t(ia) : L_.NA) * L_.TS + ts] += w;
    if (L_.JR > 0) acc[L_.delay_radius(k) + (ir >= 0 ? size_t(ir) : L_.NR) * L_.TS + ts] += w;
    double* m = acc + L_.moments(k);
    for (int part = 0; part < (turned ? 1 : 2); ++part, m += 3) {
      m[0] += w;
      m[1] += w * delay;
      m[2] += w * delay * delay;
    }
  }

  void tally_exit(bool bottom, double theta_out, const Vec3& p, double time, double wt, bool scattered,
                  double* acc) const {
    const int ia = bin_of(s_.theta_edges, theta_out);
    const int ir = bin_of(s_.r_edges, std::hypot(p.x, p.y));
    if (L_.TS > 0)
      acc[(bottom ? L_.transmit_time() : L_.reflect_time()) + time_slot(s_.time_edges, time)] += wt;
    if (bottom) {
      acc[L_.totals() + kTransmit] += wt;
      if (!scattered) acc[L_.totals() + kUnscatteredT] += wt;
      if (ia >= 0) acc[L_.transmit_angular() + ia] += wt;
      if (ir >= 0) acc[L_.transmit_radial() + ir] += wt;
    } else {
      acc[L_.totals() + kReflect] += wt;
      if (ia >= 0) acc[L_.reflect_angular() + ia] += wt;
      if (ir >= 0) acc[L_.reflect_radial() + ir] += wt;
    }
  }

  const PhotonMcSettings& s_;
  const Layout& L_;
  double sigma_t_ = 0.0, zone_len_ = 1.0, z_last_ = 0.0;
  bool slab_ = false;
};

}  // namespace

namespace {

// The tallies of each batch: a fixed set of photons (first, count), each photon its own stream.
struct Batches {
  std::vector<std::vector<double>> sums;
  std::vector<uint64_t> counts, first;
};

Batches trace_batches(const PhotonMcSettings& s, const Layout& L) {
  const int B = s.batches;
  Batches out;
  out.sums.assign(B, std::vector<double>(L.size(), 0.0));
  out.counts.resize(B);
  out.first.resize(B);
  for (int b = 0; b < B; ++b) {
    out.counts[b] = s.photons / B + (uint64_t(b) < s.photons % B ? 1 : 0);
    out.first[b] = b == 0 ? 0 : out.first[b - 1] + out.counts[b - 1];
  }
  const Tracer tracer(s, L);
  tbb::parallel_for(tbb::blocked_range<int>(0, B, 1), [&](const tbb::blocked_range<int>& range) {
    for (int b = range.begin(); b < range.end(); ++b)
      for (uint64_t i = out.first[b]; i < out.first[b] + out.counts[b]; ++i) {
        Rng rng(s.seed, i);
        tracer.trace(rng, out.sums[b].data());
      }
  });
  return out;
}

// Tally j (times scale): mean over all photons, standard error from the spread of batch means.
Estimate batch_estimate(const Batches& batches, uint64_t photons, size_t j, double scale) {
  const int B = int(batches.sums.size());
  const double N = double(photons);
  double total = 0.0;
  for (int b = 0; b < B; ++b) total += batches.sums[b][j];
  const double mean = total / N;
  double var = 0.0;
  for (int b = 0; b < B; ++b) {
    const double fb = double(batches.counts[b]) / N, xb = batches.sums[b][j] / double(batches.counts[b]);
    var += fb * fb * (xb - mean) * (xb - mean);
  }
  var *= double(B) / double(B - 1);
  double err = std::sqrt(var);
  if (err <= 1e-12 * std::abs(mean)) err = 0.0;  // a deterministic tally (the specular part)
  return Estimate{mean * scale, err * scale};
}

// The time slots from j on: before, bins, after.
TimeTally time_tally(const Batches& batches, uint64_t photons, size_t j, size_t TS) {
  TimeTally t;
  t.before = batch_estimate(batches, photons, j, 1.0);
  for (size_t i = 1; i + 1 < TS; ++i) t.bins.push_back(batch_estimate(batches, photons, j + i, 1.0));
  t.after = batch_estimate(batches, photons, j + TS - 1, 1.0);
  return t;
}

// A statistic f(m0, m1, m2) of the delay moments from j on: its value from all photons, its standard
// error from the spread of the batch values (as batch_estimate does for means).
Estimate moment_statistic(const Batches& batches, size_t j, double (*f)(double, double, double)) {
  const int B = int(batches.sums.size());
  double m[3] = {0.0, 0.0, 0.0}, N = 0.0;
  for (int b = 0; b < B; ++b) {
    for (int i = 0; i < 3; ++i) m[i] += batches.sums[b][j + i];
    N += double(batches.counts[b]);
  }
  if (!(m[0] > 0.0)) return Estimate{};
  const double value = f(m[0], m[1], m[2]);
  double var = 0.0;
  for (int b = 0; b < B; ++b) {
    const double* mb = batches.sums[b].data() + j;
    const double fb = double(batches.counts[b]) / N;
    const double xb = mb[0] > 0.0 ? f(mb[0], mb[1], mb[2]) : value;
    var += fb * fb * (xb - value) * (xb - value);
  }
  return Estimate{value, std::sqrt(var * double(B) / double(B - 1))};
}

double delay_mean(double m0, double m1, double) { return m1 / m0; }
double delay_variance(double m0, double m1, double m2) { return m2 / m0 - (m1 / m0) * (m1 / m0); }

Layout layout_of(const PhotonMcSettings& s) {
  const size_t NA = s.theta_edges.size() >= 2 ? s.theta_edges.size() - 1 : 0;
  const size_t NR = s.r_edges.size() >= 2 ? s.r_edges.size() - 1 : 0;
  const size_t TS = s.time_edges.empty() ? 0 : s.time_edges.size() + 1;
  Layout L{s.plane_depths.size(), NA, NR, TS};
  L.MS = TS > 0 ? 6 : 0;
  L.JA = s.joint_angle ? (NA + 1) * TS : 0;
  L.JR = s.joint_radius ? (NR + 1) * TS : 0;
  return L;
}

// The delay tallies of plane k (with time bins).
void add_delay_tallies(PlaneTally& t, const Batches& batches, uint64_t photons, const Layout& L, size_t k) {
  const size_t TS = L.TS;
  t.delay = time_tally(batches, photons, L.delay(k), TS);
  t.delay_weight = batch_estimate(batches, photons, L.moments(k), 1.0);
  t.delay_forward_only = time_tally(batches, photons, L.delay_forward_only(k), TS);
  t.delay_weight_forward_only = batch_estimate(batches, photons, L.moments(k) + 3, 1.0);
  t.delay_mean = moment_statistic(batches, L.moments(k), delay_mean);
  t.delay_variance = moment_statistic(batches, L.moments(k), delay_variance);
  t.delay_mean_forward_only = moment_statistic(batches, L.moments(k) + 3, delay_mean);
  t.delay_variance_forward_only = moment_statistic(batches, L.moments(k) + 3, delay_variance);
  for (size_t i = 0; L.JA > 0 && i <= L.NA; ++i)
    t.delay_angle.push_back(time_tally(batches, photons, L.delay_angle(k) + i * TS, TS));
  for (size_t i = 0; L.JR > 0 && i <= L.NR; ++i)
    t.delay_radius.push_back(time_tally(batches, photons, L.delay_radius(k) + i * TS, TS));
}

}  // namespace

PhotonMcResult run_photon_mc(const PhotonMcSettings& s) {
  validate(s);
  const Layout L = layout_of(s);
  const size_t NA = L.NA, NR = L.NR, TS = L.TS;
  const Batches batches = trace_batches(s, L);
  auto estimate = [&](size_t j, double scale) { return batch_estimate(batches, s.photons, j, scale); };
  auto solid_angle = [&](size_t i) {
    return 2.0 * kPi * (std::cos(s.theta_edges[i]) - std::cos(s.theta_edges[i + 1]));
  };
  auto area = [&](size_t i) {
    return kPi * (s.r_edges[i + 1] * s.r_edges[i + 1] - s.r_edges[i] * s.r_edges[i]);
  };

  PhotonMcResult r;
  for (size_t k = 0; k < L.P; ++k) {
    PlaneTally t;
    t.depth = s.plane_depths[k];
    for (size_t i = 0; i < NA; ++i) {
      t.angular.push_back(estimate(L.angular(k) + i, 1.0 / solid_angle(i)));
      t.angular_forward_only.push_back(estimate(L.angular_forward_only(k) + i, 1.0 / solid_angle(i)));
    }
    for (size_t i = 0; i < NR; ++i) t.radial.push_back(estimate(L.radial(k) + i, 1.0 / area(i)));
    t.unscattered = estimate(L.unscattered(k), 1.0);
    if (TS > 0) add_delay_tallies(t, batches, s.photons, L, k);
    r.planes.push_back(std::move(t));
  }
  r.specular = estimate(L.totals() + kSpecular, 1.0);
  r.diffuse_reflectance = estimate(L.totals() + kReflect, 1.0);
  r.transmittance = estimate(L.totals() + kTransmit, 1.0);
  r.unscattered_transmittance = estimate(L.totals() + kUnscatteredT, 1.0);
  r.absorbed = estimate(L.totals() + kAbsorbed, 1.0);
  for (size_t i = 0; i < NA; ++i) {
    r.reflect_angular.push_back(estimate(L.reflect_angular() + i, 1.0 / solid_angle(i)));
    r.transmit_angular.push_back(estimate(L.transmit_angular() + i, 1.0 / solid_angle(i)));
  }
  for (size_t i = 0; i < NR; ++i) {
    r.reflect_radial.push_back(estimate(L.reflect_radial() + i, 1.0 / area(i)));
    r.transmit_radial.push_back(estimate(L.transmit_radial() + i, 1.0 / area(i)));
  }
  if (TS > 0) {
    r.reflect_time = time_tally(batches, s.photons, L.reflect_time(), TS);
    r.transmit_time = time_tally(batches, s.photons, L.transmit_time(), TS);
  }
  return r;
}

}  // namespace nimbus
