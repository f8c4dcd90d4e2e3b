// A pulsed lidar into a scene's media (lidar_scene.h): photon Monte Carlo by delta tracking with
// next-event estimates through ratio tracking, and the single-scatter lidar equation along the axis.
#include "integrators/lidar_scene.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/rng.h"
#include "integrators/tracking.h"
#include "media/phase.h"
#include "nimbus/error.h"

namespace nimbus {

void validate_scene_lidar(const SceneLidarSettings& s, bool monte_carlo) {
  auto bad = [](const std::string& m) { throw Error("lidar: " + m); };
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(s.origin[a]) || !std::isfinite(s.dir[a])) bad("origin and dir must be finite");
  if (!(std::abs(length(s.dir) - 1.0) < 1e-9)) bad("dir must be a unit vector");
  if (s.channel < 0 || s.channel > 2) bad("channel must be 0, 1 or 2");
  validate_lidar_receiver(s.n, s.r_rx, s.fov, s.time_edges);
  if (monte_carlo) validate_lidar_batches(s.photons, s.batches);
}

namespace {

constexpr double kRouletteThreshold = 1e-4;  // as the slab lidar (MCML)
constexpr double kRouletteSurvival = 0.1;

// One photon history.
class SceneLidarTracer {
 public:
  SceneLidarTracer(const SceneContext& ctx, const SceneLidarSettings& s)
      : ctx_(ctx), s_(s), frame_(s.dir), cos_fov_(std::cos(s.fov)) {}

  void trace(Rng& rng, double* acc) const {
    const int ch = s_.channel;
    Vec3 p = s_.origin, d = s_.dir;
    double w = 1.0, path = 0.0;
    MediumPoint mp;
    while (true) {
      // Delta tracking to the next real collision; absorption as weight, a medium by its sigma_s.
      int medium = -1;
      Vec3 x = p;
      const bool left = track(ctx_.majorants, p, d, kInfinity, rng, [&](const Vec3& q, double maj) {
        ctx_.media.eval(q, &mp);
        const double sigma_t = mp.sigma_t()[ch];
        if (rng.uniform() * maj >= sigma_t) return true;  // a null collision
        x = q;
        w *= mp.sigma_s[ch] / sigma_t;
        medium = pick_medium(mp, rng.uniform());
        return false;
      });
      if (left) return;  // out of the media: it never comes back
      path += length(x - p);
      p = x;
      if (medium < 0 || !(w > 0.0)) return;
      // Scattering event: next-event estimate toward the receiver, then the scatter itself.
      next_event(rng, p, d, path, w, mp, acc);
      const double u1 = rng.uniform(), u2 = rng.uniform();
      d = normalize(phase_sample(ctx_.media.phase(medium), d, u1, u2));
      if (w < kRouletteThreshold) {
        if (rng.uniform() >= kRouletteSurvival) return;
        w /= kRouletteSurvival;
      }
    }
  }

 private:
  static constexpr double kInfinity = std::numeric_limits<double>::infinity();

  // The medium that scatters, in proportion to its sigma_s (-1 when none scatters).
  int pick_medium(const MediumPoint& mp, double u) const {
    double left = u * mp.sigma_s[s_.channel];
    int last = -1;
    for (int i = 0; i < mp.count; ++i) {
      const double si = mp.sigma_s_i[i][s_.channel];
      if (si <= 0.0) continue;
      last = i;
      if (left < si) return i;
      left -= si;
    }
    return last;
  }

  // Local estimate toward a point y of the receiver disk (uniform): the media's sigma_s-weighted phase
  // function toward it, the return leg's transmittance by ratio tracking, the receiver's cos / L^2 when
  // the light arrives within the FOV.  Always draws two numbers before the transmittance.
  void next_event(Rng& rng, const Vec3& p, const Vec3& d, double path, double w, const MediumPoint& mp,
                  double* acc) const {
    const int ch = s_.channel;
    const double u1 = rng.uniform(), u2 = rng.uniform();
    const double rr = s_.r_rx * std::sqrt(u1), phi = 2.0 * kPi * u2;
    const Vec3 y = s_.origin + frame_.s * (rr * std::cos(phi)) + frame_.t * (rr * std::sin(phi));
    const Vec3 delta = y - p;
    const double L = length(delta);
    if (!(L > 0.0)) return;
    const Vec3 u = delta / L;
    const double cos_r = -dot(u, s_.dir);
    if (cos_r < cos_fov_) return;
    double sp = 0.0;  // sigma_s p, summed over the media at p
    for (int i = 0; i < mp.count; ++i)
      if (mp.sigma_s_i[i][ch] > 0.0) sp += mp.sigma_s_i[i][ch] * phase_eval(ctx_.media.phase(i), dot(d, u));
    const double T = ratio_tracking_transmittance(ctx_.media, ctx_.majorants, p, u, L, rng)[ch];
    acc[lidar_time_slot(s_.time_edges, s_.n * (path + L))] += w * sp / mp.sigma_s[ch] * T * cos_r / (L * L);
  }

  const SceneContext& ctx_;
  const SceneLidarSettings& s_;
  Frame frame_;
  double cos_fov_;
};

}  // namespace

SceneLidarResult run_scene_lidar_mc(const SceneContext& ctx, const SceneLidarSettings& s) {
  validate_scene_lidar(s, true);
  const size_t TS = s.time_edges.size() + 1;  // before, the bins, after
  const SceneLidarTracer tracer(ctx, s);
  const BatchTally b = run_photon_batches(s.photons, s.batches, s.seed, TS, TS,
                                          [&](Rng& rng, double* acc) { tracer.trace(rng, acc); });
  SceneLidarResult r;
  r.received.before = b.slots[0];
  for (size_t j = 1; j + 1 < TS; ++j) r.received.bins.push_back(b.slots[j]);
  r.received.after = b.slots[TS - 1];
  r.total = b.sum;
  return r;
}

std::vector<double> scene_lidar_single_scatter(const SceneContext& ctx, const SceneLidarSettings& s) {
  validate_scene_lidar(s, false);
  constexpr int kSteps = 256;  // midpoint steps per bin
  const int ch = s.channel;
  const std::vector<double>& e = s.time_edges;
  std::vector<double> out(e.size() - 1, 0.0);
  MediumPoint mp;
  double tau = 0.0, R = 0.0;  // optical depth from the origin to range R
  // March from R to R1 in `steps` midpoint steps; on_step(Rm, h, tau at Rm, mp at Rm).
  auto march_to = [&](double R1, int steps, auto&& on_step) {
    const double h = (R1 - R) / steps;
    for (int k = 0; k < steps; ++k) {
      const double Rm = R + (k + 0.5) * h;
      ctx.media.eval(s.origin + s.dir * Rm, &mp);
      const double st = mp.sigma_t()[ch];
      on_step(Rm, h, tau + 0.5 * st * h);
      tau += st * h;
    }
    R = R1;
  };
  const double tan_fov = std::tan(s.fov);
  const double first_width = (e[1] - e[0]) / (2.0 * s.n);
  // Up to the first edge with steps no longer than the first bin's (at most 2^22 of them).
  const double gap_steps = std::ceil(e[0] / (2.0 * s.n) / first_width * kSteps);
  march_to(e[0] / (2.0 * s.n), int(std::clamp(gap_steps, double(kSteps), 4194304.0)),
           [](double, double, double) {});
  for (size_t i = 0; i + 1 < e.size(); ++i)
    march_to(e[i + 1] / (2.0 * s.n), kSteps, [&](double Rm, double h, double tau_m) {
      double sp = 0.0;  // sigma_s p(pi), summed over the media
      for (int m = 0; m < mp.count; ++m)
        if (mp.sigma_s_i[m][ch] > 0.0) sp += mp.sigma_s_i[m][ch] * phase_eval(ctx.media.phase(m), -1.0);
      const double overlap = s.r_rx > 0.0 ? std::min(1.0, std::pow(Rm * tan_fov / s.r_rx, 2)) : 1.0;
      out[i] += sp * std::exp(-2.0 * tau_m) * overlap / (Rm * Rm) * h;
    });
  return out;
}

}  // namespace nimbus
