// Black-body emission in linear Rec.709 RGB, from the tabulated CIE 1931 colour-matching functions
// (not a fitted curve): Planck's spectral radiance B(lambda, T) summed against x-bar, y-bar, z-bar over
// 360-830 nm in 1 nm steps (CIE 015:2018 sec. 7: tristimulus values as sums over the table), then CIE XYZ
// to linear RGB with the Rec.709 / sRGB primaries and the D65 white (ITU-R BT.709, IEC 61966-2-1). The
// matrix is derived here from those chromaticities. Units: B in W / (m^2 sr nm), so XYZ and RGB are
// radiances in W / (m^2 sr) (no 683 lm/W factor). Media scale it by sigma_a and an `intensity`.
#pragma once

#include <array>

#include "core/math.h"

namespace nimbus {

inline constexpr int kCieSamples = 471;     // 360 .. 830 nm
inline constexpr double kCieFirstNm = 360;  // the table's first wavelength; 1 nm apart
// x-bar, y-bar, z-bar per nm (src/media/cie1931_table.cpp, with its source).
extern const std::array<std::array<double, 3>, kCieSamples> kCie1931;

// Planck's law: spectral radiance of a black body at temperature T (kelvin) and wavelength lambda (nm),
// in W / (m^2 sr nm), with the exact SI (2019) values of h, c and k. 0 for T <= 0.
double planck_radiance(double lambda_nm, double T);
// CIE 1931 XYZ of a black body at T: sum over the table of B(lambda, T) times x-bar, y-bar, z-bar, 1 nm
// apart (W / (m^2 sr)).
Vec3 blackbody_xyz(double T);
// CIE XYZ -> linear Rec.709 RGB (sRGB primaries, D65 white: XYZ of D65 with Y = 1 maps to (1, 1, 1)).
Rgb xyz_to_rec709(const Vec3& xyz);
Vec3 rec709_to_xyz(const Rgb& rgb);

// The RGB of a black body at T (kelvin): xyz_to_rec709(blackbody_xyz(T)) with the channels that fall
// outside the gamut (blue below ~1900 K) clamped to 0, read from a table precomputed once (2 K apart up
// to 20000 K, linear in between; computed directly above). 0 for T <= 0.
Rgb blackbody_rgb(double T);

}  // namespace nimbus
