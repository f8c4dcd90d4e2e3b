// Black-body colours (media/blackbody.h).
#include "media/blackbody.h"

#include <cmath>
#include <vector>

namespace nimbus {

namespace {

// Exact SI constants (BIPM 2019).
constexpr double kPlanck = 6.62607015e-34;               // J s
constexpr double kLight = 299792458.0;                   // m / s
constexpr double kBoltzmann = 1.380649e-23;              // J / K
constexpr double kC1 = 2.0 * kPlanck * kLight * kLight;  // 2 h c^2 (W m^2 / sr)
constexpr double kC2 = kPlanck * kLight / kBoltzmann;    // h c / k (m K)

constexpr double kTableStep = 2.0;     // kelvin
constexpr double kTableMax = 20000.0;  // kelvin

using M3 = std::array<std::array<double, 3>, 3>;

M3 inverse(const M3& m) {
  M3 r;
  const double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                     m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                     m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const int a = (j + 1) % 3, b = (j + 2) % 3, c = (i + 1) % 3, d = (i + 2) % 3;
      r[i][j] = (m[a][c] * m[b][d] - m[a][d] * m[b][c]) / det;
    }
  return r;
}

// RGB -> XYZ of the Rec.709 primaries (x, y: R 0.64 0.33, G 0.30 0.60, B 0.15 0.06) and the D65 white
// (0.3127, 0.3290): the primaries' XYZ (Y = 1) as columns, each scaled so that RGB (1, 1, 1) is the white.
M3 rec709_to_xyz_matrix() {
  const double px[3] = {0.64, 0.30, 0.15}, py[3] = {0.33, 0.60, 0.06};
  const double wx = 0.3127, wy = 0.3290;
  M3 p;
  for (int c = 0; c < 3; ++c) {
    p[0][c] = px[c] / py[c];
    p[1][c] = 1.0;
    p[2][c] = (1.0 - px[c] - py[c]) / py[c];
  }
  const double white[3] = {wx / wy, 1.0, (1.0 - wx - wy) / wy};
  const M3 pinv = inverse(p);
  M3 m;
  for (int c = 0; c < 3; ++c) {
    const double s = pinv[c][0] * white[0] + pinv[c][1] * white[1] + pinv[c][2] * white[2];
    for (int r = 0; r < 3; ++r) m[r][c] = p[r][c] * s;
  }
  return m;
}

Vec3 apply(const M3& m, const Vec3& v) {
  return {m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z, m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
          m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z};
}

const M3& to_xyz() {
  static const M3 m = rec709_to_xyz_matrix();
  return m;
}
const M3& to_rgb() {
  static const M3 m = inverse(to_xyz());
  return m;
}

Rgb clamped_rgb(double T) {
  const Rgb c = xyz_to_rec709(blackbody_xyz(T));
  return {std::max(0.0, c.x), std::max(0.0, c.y), std::max(0.0, c.z)};
}

const std::vector<Rgb>& rgb_table() {
  static const std::vector<Rgb> table = [] {
    std::vector<Rgb> t(size_t(kTableMax / kTableStep) + 1);
    for (size_t i = 0; i < t.size(); ++i) t[i] = clamped_rgb(double(i) * kTableStep);
    return t;
  }();
  return table;
}

}  // namespace

double planck_radiance(double lambda_nm, double T) {
  if (!(T > 0.0)) return 0.0;
  const double l = lambda_nm * 1e-9;  // m
  const double x = kC2 / (l * T);
  if (x > 700.0) return 0.0;  // exp overflows; the radiance is far below any float
  return kC1 / (l * l * l * l * l * std::expm1(x)) * 1e-9;  // per m -> per nm
}

Vec3 blackbody_xyz(double T) {
  Vec3 xyz(0.0);
  if (!(T > 0.0)) return xyz;
  for (int i = 0; i < kCieSamples; ++i) {
    const double b = planck_radiance(kCieFirstNm + i, T);  // times d(lambda) = 1 nm
    xyz += Vec3(kCie1931[i][0], kCie1931[i][1], kCie1931[i][2]) * b;
  }
  return xyz;
}

Rgb xyz_to_rec709(const Vec3& xyz) { return apply(to_rgb(), xyz); }
Vec3 rec709_to_xyz(const Rgb& rgb) { return apply(to_xyz(), rgb); }

Rgb blackbody_rgb(double T) {
  if (!(T > 0.0)) return Rgb(0.0);
  if (T >= kTableMax) return clamped_rgb(T);
  const std::vector<Rgb>& t = rgb_table();
  const double u = T / kTableStep;
  const size_t i = size_t(u);
  const double f = u - double(i);
  return t[i] * (1.0 - f) + t[i + 1] * f;
}

}  // namespace nimbus
