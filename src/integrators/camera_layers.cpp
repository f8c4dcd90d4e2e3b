#include "integrators/camera_layers.h"

#include <cmath>

#include "integrators/tracking.h"

namespace nimbus {

double half_transmittance_fraction(const Rgb& T0, const Rgb& T1) {
  auto mean_at = [&](double u) {
    double m = 0.0;
    for (int c = 0; c < 3; ++c) m += T0[c] > 0.0 ? T0[c] * std::pow(std::max(T1[c], 0.0) / T0[c], u) : 0.0;
    return m / 3.0;
  };
  // A grey step has the closed form; a chromatic one is bisected (to ~1e-9 of the step).
  if (T0[0] == T0[1] && T0[1] == T0[2] && T1[0] == T1[1] && T1[1] == T1[2] && T1[0] > 0.0)
    return std::clamp(std::log(0.5 / T0[0]) / std::log(T1[0] / T0[0]), 0.0, 1.0);
  double lo = 0.0, hi = 1.0;
  for (int i = 0; i < 30; ++i) {
    const double mid = 0.5 * (lo + hi);
    (mean_at(mid) >= 0.5 ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

Rgb scattering_albedo(const MediumPoint& mp) {
  const Rgb sigma_t = mp.sigma_t();
  Rgb a(0.0);
  for (int c = 0; c < 3; ++c) a[c] = sigma_t[c] > 0.0 ? mp.sigma_s[c] / sigma_t[c] : 0.0;
  return a;
}

void march_depth(const SceneMedia& media, const MajorantGrid& grid, const Vec3& o, const Vec3& d,
                 double tau_step, CameraSample* sample, double tmax) {
  Rgb T(1.0);
  MediumPoint mp;
  march(grid, o, d, tmax, tau_step, 0.5, [&](const Vec3& p, double t, double dt) {
    media.eval(p, &mp);
    const Rgb T1 = T * exp_channels(-mp.sigma_t() * dt);
    if (average(T1) < 0.5) {
      sample->depth = t - 0.5 * dt + dt * half_transmittance_fraction(T, T1);
      sample->albedo = scattering_albedo(mp);
      return false;
    }
    T = T1;
    return true;
  });
}

}  // namespace nimbus
