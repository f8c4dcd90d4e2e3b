// The lidar models of lidar.h: the single-scatter lidar equation in closed form and the seed's fused
// algorithm in time (docs/validation/lidar.md derives both).
//
// Fused model.  The phase function is split (phase_split.h, f = g^2) into a forward peak, carried by the
// corrected MFS propagator with peak scattering b_p = f b and per-component theta2 of the peak, and a wide
// part whose scatters remove light from the narrow beams (loss l = a + (1 - f) b).  At depth z a leg
// (out, or by reciprocity the receiver's beam launched from the disk into the FOV) holds unscattered
// light U = exp(-c z) and peak-scattered light S = W / cosh x (mfs_kernel.h) spread over the plane with
// per-component variance sig_r^2, in angle sig_a^2, and delayed by the kernel's delay law (time.md).
// Light back-scattered at depth z reaches the receiver with (per unit z, per unit receiver area)
//   b [ U^2 K(0) pbar(0) + 2 U S K(sig_r^2) pbar(sig_a^2) + S^2 K(2 sig_r^2) pbar(2 sig_a^2) ]
// where K(s^2) = int d^2rho Gauss_{s^2}(rho) F(rho) overlaps the outgoing beam with the receiver's
// footprint F(rho) = |disk(r_rx) n disk(rho, z tan fov)| / (pi r_rx^2 z^2) (1(rho < z tan fov) / z^2 for a
// point receiver), and pbar(s^2) averages p(pi - theta) over a Rayleigh angle of per-component variance
// s^2.  Its time is n (2 z + tau_out + tau_ret): the delay of each scattered leg from the MFS delay
// density, the two legs independent; nothing arrives before 2 n z (seed eq. 17's step).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "nimbus/error.h"
#include "transport/fresnel.h"
#include "transport/lidar.h"
#include "transport/mfs_kernel.h"
#include "transport/phase_split.h"
#include "transport/time_resolved.h"

namespace nimbus {

double disk_overlap_area(double r1, double r2, double d) {
  if (r1 <= 0.0 || r2 <= 0.0 || d >= r1 + r2) return 0.0;
  const double rmin = std::min(r1, r2);
  if (d <= std::abs(r1 - r2)) return kPi * rmin * rmin;
  const double a1 = std::acos(std::clamp((d * d + r1 * r1 - r2 * r2) / (2.0 * d * r1), -1.0, 1.0));
  const double a2 = std::acos(std::clamp((d * d + r2 * r2 - r1 * r1) / (2.0 * d * r2), -1.0, 1.0));
  const double k = (-d + r1 + r2) * (d + r1 - r2) * (d - r1 + r2) * (d + r1 + r2);
  return r1 * r1 * a1 + r2 * r2 * a2 - 0.5 * std::sqrt(std::max(0.0, k));
}

namespace {

// 16-point Gauss-Legendre on [-1, 1] (Abramowitz & Stegun 25.4.30), half the symmetric nodes.
constexpr double kX[8] = {0.0950125098376374, 0.2816035507792589, 0.4580167776572274, 0.6178762444026438,
                          0.7554044083550030, 0.8656312023878318, 0.9445750230732326, 0.9894009349916499};
constexpr double kW[8] = {0.1894506104550685, 0.1826034150449236, 0.1691565193950025, 0.1495959888165767,
                          0.1246289712555339, 0.0951585116824928, 0.0622535239386479, 0.0271524594117541};

template <class F>
double gauss16(double lo, double hi, F f) {
  const double c = 0.5 * (lo + hi), h = 0.5 * (hi - lo);
  double s = 0.0;
  for (int i = 0; i < 8; ++i) s += kW[i] * (f(c - h * kX[i]) + f(c + h * kX[i]));
  return s * h;
}

// The receiver's footprint at range R: received irradiance per unit area of light leaving the plane at
// transverse distance rho straight back toward the receiver, per unit radiance (small angles).
double footprint(const LidarSettings& s, double rho, double R) {
  const double Rc = R * std::tan(s.fov);  // radius of the FOV's cone at range R
  if (s.r_rx <= 0.0) return rho < Rc ? 1.0 / (R * R) : 0.0;
  return disk_overlap_area(s.r_rx, Rc, rho) / (kPi * s.r_rx * s.r_rx * R * R);
}

// K(s2): the footprint at range R averaged over a 2-D Gaussian of per-component variance s2 on the axis.
double overlap(const LidarSettings& s, double s2, double R) {
  const double Rc = R * std::tan(s.fov);
  if (s.r_rx <= 0.0) return -std::expm1(-Rc * Rc / (2.0 * s2)) / (R * R);
  const double far = std::min(s.r_rx + Rc, 10.0 * std::sqrt(s2));
  auto f = [&](double rho) { return rho * std::exp(-rho * rho / (2.0 * s2)) / s2 * footprint(s, rho, R); };
  const double kink = std::abs(s.r_rx - Rc);
  if (kink < far) return gauss16(0.0, kink, f) + gauss16(kink, far, f);
  return gauss16(0.0, 0.5 * far, f) + gauss16(0.5 * far, far, f);
}

// pbar(s2): p(pi - theta) averaged over a Rayleigh angle theta of per-component variance s2.
double back_phase(const Phase& phase, double s2) {
  if (!(s2 > 1e-12)) return phase_eval(phase, -1.0);
  const double hi = std::min(kPi, 8.0 * std::sqrt(s2));
  auto f = [&](double th) {
    return phase_eval(phase, -std::cos(th)) * th / s2 * std::exp(-th * th / (2.0 * s2));
  };
  return (gauss16(0.0, 0.25 * hi, f) + gauss16(0.25 * hi, hi, f)) / -std::expm1(-hi * hi / (2.0 * s2));
}

// e^x E1(x), x > 0: the series of E1 below 1, its continued fraction above (Numerical Recipes 6.3).
double scaled_e1(double x) {
  if (x < 1.0) return std::exp(x) * -std::expint(-x);
  double b = x + 1.0, c = 1e300, d = 1.0 / b, h = d;
  for (int i = 1; i < 200; ++i) {
    const double an = -double(i) * i;
    b += 2.0;
    d = 1.0 / (an * d + b);
    c = b + an / c;
    const double del = c * d;
    h *= del;
    if (std::abs(del - 1.0) < 1e-15) break;
  }
  return h;
}

// int exp(-alpha (R - d)) overlap(R) / R^2 dR over ranges [R1, R2] (d = s.distance), overlap(R) =
// min(1, (R tan fov / r_rx)^2): closed forms below and above R_o = r_rx / tan fov.
double single_scatter_integral(const LidarSettings& s, double alpha, double R1, double R2) {
  if (!(R2 > R1)) return 0.0;
  const double Ro = s.r_rx / std::tan(s.fov), d = s.distance;
  double sum = 0.0;
  if (R1 < Ro) {  // exp(-alpha (R - d)) / Ro^2
    const double hi = std::min(R2, Ro);
    sum += (alpha > 0.0 ? (std::exp(-alpha * (R1 - d)) - std::exp(-alpha * (hi - d))) / alpha : hi - R1) /
           (Ro * Ro);
    R1 = hi;
  }
  if (R2 >
      R1) {  // e^{-alpha (R - d)} / R^2 = d/dR [e^{-alpha (R - d)} (alpha e^{alpha R} E1(alpha R) - 1/R)]
    if (R1 <= 0.0) return std::numeric_limits<double>::infinity();
    auto G = [&](double R) {
      return std::exp(-alpha * (R - d)) * ((alpha > 0.0 ? alpha * scaled_e1(alpha * R) : 0.0) - 1.0 / R);
    };
    sum += G(R2) - G(R1);
  }
  return sum;
}

// The single-scatter return from depths [z1, z2] of the slab.
double single_scatter(const LidarSettings& s, double z1, double z2) {
  if (!(s.sigma_s > 0.0)) return 0.0;
  return s.sigma_s * phase_eval(s.phase, -1.0) *
         single_scatter_integral(s, 2.0 * (s.sigma_s + s.sigma_a), s.distance + z1, s.distance + z2);
}

// The depth in the slab whose single-scatter return arrives at time t.
double depth_at(const LidarSettings& s, double t) {
  return std::clamp(t / (2.0 * s.n) - s.distance, 0.0, s.thickness);
}

// Spreads `mass` uniformly over times [t0, t1) into the bins (slot 0: before, last: after).
void deposit(const std::vector<double>& edges, double t0, double t1, double mass,
             std::vector<double>& slots) {
  if (!(mass != 0.0)) return;
  if (!(t1 > t0)) t1 = t0 * (1.0 + 1e-15) + 1e-300;
  const double rate = mass / (t1 - t0);
  size_t i = size_t(std::upper_bound(edges.begin(), edges.end(), t0) - edges.begin());
  double lo = t0;
  while (lo < t1) {
    const double hi = i < edges.size() ? std::min(t1, edges[i]) : t1;
    slots[i] += rate * (hi - lo);
    lo = hi;
    ++i;
  }
}

// With a Fresnel surface: light from depth h arrives at t = 2 d + 2 n h with
//   sigma_s p(pi) T0^2 exp(-2 c h) O(h) / (h + n d)^2 dh
// (T0 = 1 - R(0) each way; the on-axis ray tube's spread (h + n d)^2 of fresnel.h; O the share of the disk
// that sees the axis point within the FOV: its radius there z0 tan fov + h tan(asin(sin fov / n))), by
// Simpson's rule on 2000 steps per bin.
double single_scatter_fresnel(const LidarSettings& s, double t0, double t1) {
  auto depth = [&](double t) { return std::clamp((t - 2.0 * s.distance) / (2.0 * s.n), 0.0, s.thickness); };
  const double h0 = depth(t0), h1 = depth(t1);
  if (!(h1 > h0) || !(s.sigma_s > 0.0)) return 0.0;
  const double T0 = 1.0 - fresnel_reflectance(1.0, s.n), c = s.sigma_s + s.sigma_a;
  const double tan_w = std::tan(std::asin(std::sin(s.fov) / s.n)), tan_a = std::tan(s.fov);
  auto f = [&](double h) {
    const double reach = s.distance * tan_a + h * tan_w;
    const double overlap = s.r_rx > 0.0 ? std::min(1.0, (reach / s.r_rx) * (reach / s.r_rx)) : 1.0;
    return std::exp(-2.0 * c * h) * overlap / ((h + s.n * s.distance) * (h + s.n * s.distance));
  };
  const int N = 2000;
  const double dh = (h1 - h0) / N;
  double sum = f(h0) + f(h1);
  for (int i = 1; i < N; ++i) sum += f(h0 + i * dh) * (i % 2 ? 4.0 : 2.0);
  return s.sigma_s * phase_eval(s.phase, -1.0) * T0 * T0 * sum * dh / 3.0;
}

}  // namespace

double lidar_surface_return(const LidarSettings& s) {
  const double R0 = fresnel_reflectance(1.0, s.n);
  return s.r_rx > 0.0 ? R0 / (kPi * s.r_rx * s.r_rx) : std::numeric_limits<double>::infinity();
}

std::vector<double> lidar_single_scatter(const LidarSettings& s) {
  validate_lidar(s, false);
  std::vector<double> bins;
  if (s.fresnel) {
    for (size_t i = 0; i + 1 < s.time_edges.size(); ++i)
      bins.push_back(single_scatter_fresnel(s, s.time_edges[i], s.time_edges[i + 1]));
    return bins;
  }
  for (size_t i = 0; i + 1 < s.time_edges.size(); ++i)
    bins.push_back(single_scatter(s, depth_at(s, s.time_edges[i]), depth_at(s, s.time_edges[i + 1])));
  return bins;
}

namespace {

// One leg's delay law at depth z on M cells of width h from 0: cell masses as fractions of the leg's
// scattered light (Simpson's rule on the MFS delay density), normalised with the exact tail beyond M h
// so that the cells and the tail hold all of it.
std::vector<double> leg_delay_cells(double z, double bp, double loss, double theta2, double h, int M) {
  std::vector<double> m(M);
  double f0 = mfs_delay_density(0.0, z, bp, loss, theta2), sum = 0.0;
  for (int k = 0; k < M; ++k) {
    const double fm = mfs_delay_density((k + 0.5) * h, z, bp, loss, theta2);
    const double f1 = mfs_delay_density((k + 1.0) * h, z, bp, loss, theta2);
    m[k] = h * (f0 + 4.0 * fm + f1) / 6.0;
    sum += m[k];
    f0 = f1;
  }
  const double tail = mfs_delay_within(M * h, std::numeric_limits<double>::infinity(), z, bp, loss, theta2);
  for (double& x : m) x /= sum + tail;
  return m;
}

struct Leg {
  double U = 0.0, S = 0.0, var_r = 0.0, var_a = 0.0;
};

// The scattered terms of the fused model from the slab of depths [z0, z0 + dz], into slots.
void scattered_terms(const LidarSettings& s, const PhaseSplit& split, double z0, double dz,
                     std::vector<double>& slots) {
  const double z = z0 + 0.5 * dz, b = s.sigma_s, c = s.sigma_s + s.sigma_a, range = s.distance + z;
  const double bp = split.f() * b, loss = s.sigma_a + (1.0 - split.f()) * b, theta2 = split.theta2();
  if (!(bp > 0.0 && theta2 > 0.0)) return;
  const GaussianBeam gb = gaussian_beam(GaussianModel::Mfs, z, bp * z, loss * z, theta2);
  const Leg leg{std::exp(-c * z), gb.total, gb.var_radius, gb.var_angle};
  const double one = 2.0 * b * leg.U * leg.S * overlap(s, leg.var_r, range) * back_phase(s.phase, leg.var_a);
  const double two =
      b * leg.S * leg.S * overlap(s, 2.0 * leg.var_r, range) * back_phase(s.phase, 2.0 * leg.var_a);
  // Delay cells: out to 32 T z^2 (the law is below 1e-20 of its peak beyond), or to the last edge.
  const double Tz2 = theta2 * bp / -std::expm1(-bp * z) * z * z;
  const double t_first = 2.0 * s.n * (s.distance + z0), t_last = s.time_edges.back();
  const int M = 256;
  const double span = std::max(std::min(32.0 * Tz2, t_last / s.n - 2.0 * (s.distance + z0)), 1e-9 * Tz2);
  const double h = span / M;
  // A cell's light is spread in time over the depth cell and the delay cell (widths h/2, one leg; h, two).
  const double tw1 = 2.0 * s.n * dz + 0.5 * s.n * h, tw2 = 2.0 * s.n * dz + s.n * h;
  const std::vector<double> m = leg_delay_cells(z, bp, loss, theta2, 0.5 * h, 2 * M);
  // One leg scattered: delay tau; both: tau_out + tau_ret (cells of width h/2 summed pairwise).
  double sum1 = 0.0, sum2 = 0.0;
  for (int j = 0; j < 2 * M; ++j) {
    double cj = 0.0;
    for (int k = 0; k <= j; ++k) cj += m[k] * m[j - k];
    const double t0 = t_first + s.n * 0.5 * h * j;
    deposit(s.time_edges, t0, t0 + tw2, two * dz * cj, slots);
    deposit(s.time_edges, t0, t0 + tw1, one * dz * m[j], slots);
    sum1 += m[j];
    sum2 += cj;
  }
  // What lies beyond the cells arrives after the last edge (or, uncapped, is below rounding).
  slots.back() += dz * (one * std::max(0.0, 1.0 - sum1) + two * std::max(0.0, 1.0 - sum2));
}

}  // namespace

LidarModelResult lidar_mfs(const LidarSettings& s) {
  validate_lidar(s, false);
  if (s.fresnel) throw Error("lidar: the fused model (mfs) has no Fresnel surface (use mc, single)");
  const std::vector<double>& edges = s.time_edges;
  std::vector<double> slots(edges.size() + 1, 0.0);
  // Depth cells: fine enough that one cell spans at most half the narrowest bin in time.
  double narrow = edges.back() - edges.front();
  for (size_t i = 0; i + 1 < edges.size(); ++i) narrow = std::min(narrow, edges[i + 1] - edges[i]);
  const double z_end = depth_at(s, edges.back());
  const int cells = int(std::clamp(4.0 * s.n * z_end / narrow, 200.0, 4000.0));
  if (s.sigma_s > 0.0) {
    const PhaseSplit split(s.phase, g2_peak_fraction(s.phase), true);
    for (int i = 0; z_end > 0.0 && i < cells; ++i)
      scattered_terms(s, split, z_end * i / cells, z_end / cells, slots);
    // Depths beyond the last edge's reach: all of it arrives after the last edge.
    const double rest = s.thickness - z_end;
    for (int i = 0; rest > 0.0 && i < 100; ++i)
      scattered_terms(s, split, z_end + rest * i / 100, rest / 100, slots);
  }
  LidarModelResult r;
  r.single = lidar_single_scatter(s);
  r.before = slots.front() + single_scatter(s, 0.0, depth_at(s, edges.front()));
  r.after = slots.back() + single_scatter(s, z_end, s.thickness);
  for (size_t i = 0; i + 1 < edges.size(); ++i) r.bins.push_back(r.single[i] + slots[i + 1]);
  return r;
}

}  // namespace nimbus
