// Photon Monte Carlo of a lidar return (lidar.h): next-event estimation toward the receiver at every
// scattering event, binned by total path length, with batch-mean standard errors.
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "core/rng.h"
#include "nimbus/error.h"
#include "transport/fresnel.h"
#include "transport/lidar.h"
#include "transport/time_resolved.h"

namespace nimbus {

void validate_lidar_receiver(double n, double r_rx, double fov, const std::vector<double>& time_edges) {
  auto bad = [](const std::string& m) { throw Error("lidar: " + m); };
  if (!(n >= 1.0) || !(n <= 10.0)) bad("n must lie in [1, 10]");
  if (!(r_rx >= 0.0) || !std::isfinite(r_rx)) bad("receiver radius must be finite and >= 0");
  if (!(fov > 0.0) || !(fov < 0.5 * kPi)) bad("fov (half-angle) must lie in (0, pi/2)");
  if (time_edges.size() < 2) bad("time edges need at least two values");
  if (time_edges.size() - 1 > kMaxTimeEdgeBins) bad(fmt::format("at most {} time bins", kMaxTimeEdgeBins));
  for (size_t i = 0; i < time_edges.size(); ++i) {
    if (!(time_edges[i] >= 0.0) || !std::isfinite(time_edges[i])) bad("time edges must be finite and >= 0");
    if (i > 0 && !(time_edges[i] > time_edges[i - 1])) bad("time edges must increase");
  }
}

void validate_lidar_batches(uint64_t photons, int batches) {
  if (batches < 2) throw Error("lidar: needs at least 2 batches");
  if (photons < uint64_t(batches)) throw Error("lidar: needs at least one photon per batch");
}

void validate_lidar(const LidarSettings& s, bool monte_carlo) {
  auto bad = [](const std::string& m) { throw Error("lidar: " + m); };
  if (!(s.sigma_s >= 0.0) || !std::isfinite(s.sigma_s)) bad("sigma_s must be finite and >= 0");
  if (!(s.sigma_a >= 0.0) || !std::isfinite(s.sigma_a)) bad("sigma_a must be finite and >= 0");
  if (!std::isfinite(s.sigma_s + s.sigma_a)) bad("sigma_s + sigma_a must be finite");
  if (!(s.thickness > 0.0) || !std::isfinite(s.thickness)) bad("thickness must be finite and > 0");
  if (!(s.distance >= 0.0) || !std::isfinite(s.distance)) bad("distance must be finite and >= 0");
  validate_lidar_receiver(s.n, s.r_rx, s.fov, s.time_edges);
  if (s.fresnel && !(s.distance > 0.0)) bad("a Fresnel surface needs a gap (distance > 0)");
  if (monte_carlo) validate_lidar_batches(s.photons, s.batches);
}

size_t lidar_time_slot(const std::vector<double>& edges, double t) {
  if (t < edges.front()) return 0;
  if (t >= edges.back()) return edges.size();
  return size_t(std::upper_bound(edges.begin(), edges.end(), t) - edges.begin());
}

namespace {

constexpr double kRouletteThreshold = 1e-4;  // MCML
constexpr double kRouletteSurvival = 0.1;

// Accumulator slots: [0, TS) time slots (before, bins, after), then the analog tally.
struct LidarLayout {
  size_t TS;
  size_t analog() const { return TS; }
  size_t size() const { return TS + 1; }
};

// One photon history.
class LidarTracer {
 public:
  LidarTracer(const LidarSettings& s, const LidarLayout& L)
      : s_(s), L_(L), sigma_t_(s.sigma_s + s.sigma_a), cos_fov_(std::cos(s.fov)) {}

  void trace(Rng& rng, double* acc) const {
    if (!(sigma_t_ > 0.0)) return;  // nothing scatters: nothing returns
    const double albedo = s_.sigma_s / sigma_t_;
    const double z0 = s_.distance, z1 = s_.distance + s_.thickness;
    Vec3 p(0.0, 0.0, z0), d(0.0, 0.0, 1.0);  // across the clear gap to the near face
    double w = s_.fresnel ? 1.0 - fresnel_reflectance(1.0, s_.n) : 1.0, path = z0;
    while (true) {
      // Free flight; a photon reaching a face leaves (matched boundaries; a Fresnel top face reflects).
      const double step = -std::log(1.0 - rng.uniform()) / sigma_t_;
      const double s_face = d.z > 0.0 ? (z1 - p.z) / d.z : d.z < 0.0 ? (z0 - p.z) / d.z : 1e300;
      if (step >= s_face) {
        if (d.z < 0.0 && reflects(rng, p, d, path, s_face)) continue;
        if (d.z < 0.0) tally_analog(p + d * s_face, d, w, acc);
        return;
      }
      p += d * step;
      path += step;
      // Scattering event: next-event estimate toward the receiver, then the scatter itself.
      w *= albedo;
      next_event(rng, p, d, path, w, acc);
      const double u1 = rng.uniform(), u2 = rng.uniform();
      d = normalize(phase_sample(s_.phase, d, u1, u2));
      if (w < kRouletteThreshold) {
        if (rng.uniform() >= kRouletteSurvival) return;
        w /= kRouletteSurvival;
      }
    }
  }

 private:
  // At the Fresnel surface, from below: reflected with probability R (then continues from the surface
  // point, mirrored); false where the photon leaves (matched faces: always).
  bool reflects(Rng& rng, Vec3& p, Vec3& d, double& path, double s_face) const {
    if (!s_.fresnel) return false;
    const double R = fresnel_reflectance(-d.z, 1.0 / s_.n);
    if (!(R > 0.0) || rng.uniform() >= R) return false;
    p += d * s_face;
    p.z = s_.distance;
    path += s_face;
    d.z = -d.z;
    return true;
  }

  // Local estimate: scatter toward a point y of the receiver (uniform on the disk), no collision on the
  // way back (exp(-sigma_t L_in), L_in the part inside the slab), received irradiance cos / L^2 if the
  // arriving direction lies within the FOV.  Always draws two numbers (the same stream for any FOV).
  void next_event(Rng& rng, const Vec3& p, const Vec3& d, double path, double w, double* acc) const {
    const double u1 = rng.uniform(), u2 = rng.uniform();
    const double rr = s_.r_rx * std::sqrt(u1), phi = 2.0 * kPi * u2;
    const Vec3 delta = Vec3(rr * std::cos(phi), rr * std::sin(phi), 0.0) - p;
    const double L = length(delta);
    if (!(L > 0.0) || !(p.z > 0.0)) return;
    if (s_.fresnel) return next_event_fresnel(p, d, delta, path, w, acc);
    const Vec3 u = delta / L;
    const double cos_r = -u.z;  // angle between the arriving direction and the receiver's axis (-z)
    if (cos_r < cos_fov_) return;
    const double inside = L * (p.z - s_.distance) / p.z;  // the part of the return leg in the slab
    const double e = w * phase_eval(s_.phase, dot(d, u)) * std::exp(-sigma_t_ * inside) * cos_r / (L * L);
    acc[lidar_time_slot(s_.time_edges, s_.n * (path + L))] += e;
  }

  // The same through the Fresnel surface: the refracted path to y (fresnel.h), the water's phase function
  // toward its lower leg, the surface's transmittance, the ray tube's spread instead of L^2 / cos; the FOV
  // on the air leg; time z0 in the gap down, n times the water path, the air leg back.
  void next_event_fresnel(const Vec3& p, const Vec3& d, const Vec3& delta, double path, double w,
                          double* acc) const {
    const double z0 = s_.distance, h = p.z - z0, rho = std::hypot(delta.x, delta.y);
    if (!(h > 0.0)) return;
    const RefractedPath rp = refracted_path(h, z0, rho, s_.n);
    if (rp.cos_a < cos_fov_) return;
    const double ux = rho > 0.0 ? delta.x / rho : 0.0, uy = rho > 0.0 ? delta.y / rho : 0.0;
    const Vec3 u_w(ux * rp.a / rp.L_w, uy * rp.a / rp.L_w, -rp.cos_w);
    const double T = 1.0 - fresnel_reflectance(rp.cos_w, 1.0 / s_.n);
    const double e = w * phase_eval(s_.phase, dot(d, u_w)) * T * std::exp(-sigma_t_ * rp.L_w) / rp.spread;
    acc[lidar_time_slot(s_.time_edges, z0 + s_.n * (path - z0 + rp.L_w) + rp.L_a)] += e;
  }

  // The analog tally: a photon leaving through the near face that crosses the gap into the disk within
  // the FOV.
  void tally_analog(const Vec3& exit, const Vec3& d_in, double w, double* acc) const {
    Vec3 d = d_in;
    if (s_.fresnel) {  // refracted into the air (the reflected part was sampled away by reflects())
      const double sin2 = s_.n * s_.n * (1.0 - d.z * d.z);
      if (sin2 >= 1.0) return;
      d = Vec3(s_.n * d.x, s_.n * d.y, -std::sqrt(1.0 - sin2));
    }
    const Vec3 at = exit + d * (exit.z / -d.z);  // where it meets the plane of the receiver
    if (s_.r_rx > 0.0 && std::hypot(at.x, at.y) < s_.r_rx && -d.z >= cos_fov_)
      acc[L_.analog()] += w / (kPi * s_.r_rx * s_.r_rx);
  }

  const LidarSettings& s_;
  const LidarLayout& L_;
  double sigma_t_, cos_fov_;
};

}  // namespace

BatchTally run_photon_batches(uint64_t photons, int batches, uint64_t seed, size_t slots, size_t summed,
                              const std::function<void(Rng&, double*)>& trace) {
  const int B = batches;
  std::vector<std::vector<double>> sums(B, std::vector<double>(slots, 0.0));
  std::vector<uint64_t> first(B), counts(B);
  for (int i = 0; i < B; ++i) {
    counts[i] = photons / B + (uint64_t(i) < photons % B ? 1 : 0);
    first[i] = i == 0 ? 0 : first[i - 1] + counts[i - 1];
  }
  tbb::parallel_for(tbb::blocked_range<int>(0, B, 1), [&](const tbb::blocked_range<int>& range) {
    for (int i = range.begin(); i < range.end(); ++i)
      for (uint64_t k = first[i]; k < first[i] + counts[i]; ++k) {
        Rng rng(seed, k);
        trace(rng, sums[i].data());
      }
  });
  // Mean over all photons of f(batch sums), standard error from the spread of batch means.
  const double N = double(photons);
  auto batch_mean = [&](auto f) {
    double total = 0.0;
    for (int i = 0; i < B; ++i) total += f(sums[i]);
    const double mean = total / N;
    double var = 0.0;
    for (int i = 0; i < B; ++i) {
      const double fb = double(counts[i]) / N, xb = f(sums[i]) / double(counts[i]);
      var += fb * fb * (xb - mean) * (xb - mean);
    }
    return Estimate{mean, std::sqrt(var * double(B) / double(B - 1))};
  };
  BatchTally r;
  for (size_t j = 0; j < slots; ++j) r.slots.push_back(batch_mean([j](const auto& v) { return v[j]; }));
  r.sum = batch_mean([&](const auto& v) {
    double t = 0.0;
    for (size_t j = 0; j < summed; ++j) t += v[j];
    return t;
  });
  return r;
}

LidarMcResult run_lidar_mc(const LidarSettings& s) {
  validate_lidar(s, true);
  const LidarLayout L{s.time_edges.size() + 1};
  const LidarTracer tracer(s, L);
  const BatchTally b = run_photon_batches(s.photons, s.batches, s.seed, L.size(), L.TS,
                                          [&](Rng& rng, double* acc) { tracer.trace(rng, acc); });
  LidarMcResult r;
  r.received.before = b.slots[0];
  for (size_t j = 1; j + 1 < L.TS; ++j) r.received.bins.push_back(b.slots[j]);
  r.received.after = b.slots[L.TS - 1];
  r.total = b.sum;
  r.analog = b.slots[L.analog()];
  return r;
}

}  // namespace nimbus
