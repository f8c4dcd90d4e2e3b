// Black-body colours from the tabulated CIE 1931 functions (media/blackbody.h), against published
// chromaticities of the Planckian locus.
#include "media/blackbody.h"

#include <gtest/gtest.h>

#include <cmath>

namespace nimbus {
namespace {

// x, y of XYZ.
std::pair<double, double> chromaticity(const Vec3& c) {
  const double s = c.x + c.y + c.z;
  return {c.x / s, c.y / s};
}

// Robertson (1968), J. Opt. Soc. Am. 58, 1528, reprinted in Wyszecki & Stiles, Color Science (2nd ed.
// 1982), Table 1(3.11): the CIE 1960 (u, v) of the Planckian locus at reciprocal temperatures (mired).
// x = 3u / (2u - 8v + 4), y = 2v / (2u - 8v + 4).
struct LocusPoint {
  double mired, u, v;
};
constexpr LocusPoint kRobertson[] = {{100, 0.19032, 0.29326},   // 10000 K
                                     {150, 0.19962, 0.30921},   // 6667 K
                                     {200, 0.21142, 0.32312},   // 5000 K
                                     {250, 0.22511, 0.33439},   // 4000 K
                                     {400, 0.27218, 0.35407},   // 2500 K
                                     {500, 0.30505, 0.35907},   // 2000 K
                                     {600, 0.33724, 0.36051}};  // 1667 K

TEST(Blackbody, ChromaticityMatchesRobertsonTable) {
  for (const LocusPoint& p : kRobertson) {
    const double den = 2.0 * p.u - 8.0 * p.v + 4.0;
    const double x = 3.0 * p.u / den, y = 2.0 * p.v / den;
    const auto [bx, by] = chromaticity(blackbody_xyz(1e6 / p.mired));
    EXPECT_NEAR(bx, x, 1e-3) << p.mired << " mired";
    EXPECT_NEAR(by, y, 1e-3) << p.mired << " mired";
  }
}

// CIE standard illuminant A: a Planckian radiator at 2856 K, x = 0.44757, y = 0.40745 (CIE 015:2018,
// Table T.3 / ISO 11664-2).
TEST(Blackbody, IlluminantA) {
  const auto [x, y] = chromaticity(blackbody_xyz(2856.0));
  EXPECT_NEAR(x, 0.44757, 1e-3);
  EXPECT_NEAR(y, 0.40745, 1e-3);
}

// The table-driven RGB, converted back to XYZ, has the tabulated chromaticity where the colour is inside
// the Rec.709 gamut (no channel clamped).
TEST(Blackbody, RgbTableKeepsChromaticity) {
  for (const double T : {2500.0, 2856.0, 4000.0, 5000.0, 6500.0, 10000.0, 25000.0}) {
    const Rgb rgb = blackbody_rgb(T + 1.0);  // between two table entries
    const auto [x, y] = chromaticity(rec709_to_xyz(rgb));
    const auto [ex, ey] = chromaticity(blackbody_xyz(T + 1.0));
    EXPECT_NEAR(x, ex, 1e-4) << T;
    EXPECT_NEAR(y, ey, 1e-4) << T;
    const double Y = rec709_to_xyz(rgb).y;
    EXPECT_NEAR(Y / blackbody_xyz(T + 1.0).y, 1.0, 1e-4) << T;
  }
}

// The D65 white point maps to equal RGB; the primaries' chromaticities come back.
TEST(Blackbody, Rec709Matrix) {
  const Vec3 d65(0.3127 / 0.3290, 1.0, (1.0 - 0.3127 - 0.3290) / 0.3290);
  const Rgb w = xyz_to_rec709(d65);
  EXPECT_NEAR(w.x, 1.0, 1e-12);
  EXPECT_NEAR(w.y, 1.0, 1e-12);
  EXPECT_NEAR(w.z, 1.0, 1e-12);
  const auto [rx, ry] = chromaticity(rec709_to_xyz(Rgb(1, 0, 0)));
  EXPECT_NEAR(rx, 0.64, 1e-12);
  EXPECT_NEAR(ry, 0.33, 1e-12);
  // The matrix of SMPTE RP 177 from these chromaticities (first column: 3.2409699, -0.9692436,
  // 0.0556301; IEC 61966-2-1 rounds it to 3.2406, -0.9689, 0.0557).
  const Rgb r = xyz_to_rec709(Vec3(1, 0, 0));
  EXPECT_NEAR(r.x, 3.2409699, 1e-6);
  EXPECT_NEAR(r.y, -0.9692436, 1e-6);
  EXPECT_NEAR(r.z, 0.0556301, 1e-6);
}

// Planck's law against the Stefan-Boltzmann law: the radiance integrated over all wavelengths is
// sigma T^4 / pi (checked by a fine quadrature of planck_radiance well beyond the visible).
TEST(Blackbody, PlanckIntegratesToStefanBoltzmann) {
  const double T = 5000.0, sigma = 5.670374419e-8;
  double sum = 0.0;
  for (double l = 10.0; l < 200000.0; l += 1.0) sum += planck_radiance(l + 0.5, T);
  EXPECT_NEAR(sum / (sigma * std::pow(T, 4) / 3.14159265358979), 1.0, 1e-4);
}

TEST(Blackbody, ColdIsBlack) {
  EXPECT_EQ(blackbody_rgb(0.0), Rgb(0.0));
  EXPECT_EQ(blackbody_rgb(-5.0), Rgb(0.0));
  EXPECT_LT(max_component(blackbody_rgb(300.0)), 1e-20);
  // Low temperatures are red: blue clamped to 0, red above green.
  const Rgb c = blackbody_rgb(1200.0);
  EXPECT_EQ(c.z, 0.0);
  EXPECT_GT(c.x, c.y);
}

}  // namespace
}  // namespace nimbus
