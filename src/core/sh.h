// Real spherical harmonics Y_lm of a unit vector, bands l < kShMaxBands, orthonormal on the sphere
// (int Y_lm Y_l'm' dw = delta), index l^2 + l + m. Built from Re/Im (x + i y)^m and the polynomial
// part of the associated Legendre functions, so there is no division by sin(theta) at the poles.
// Only sums over m are used (sum_m Y_lm(a) Y_lm(b) = (2l + 1) / (4 pi) P_l(a . b)), which do not
// depend on the sign convention.
#pragma once

#include <algorithm>
#include <cmath>

#include "core/math.h"

namespace nimbus {

inline constexpr int kShMaxBands = 6;

// The normalisations of sh_eval, per (l, m), m <= l: K_lm = sqrt((2l + 1) / (4 pi) (l - m)! / (l + m)!),
// times sqrt(2) for m != 0; and (-1)^m (2m - 1)!!, where the recurrence for Q_l^m starts. Found once
// (the same operations as per call before: sh_eval's values are the same bits).
struct ShFactors {
  double k[kShMaxBands][kShMaxBands] = {};
  double q0[kShMaxBands] = {};
  ShFactors() {
    for (int m = 0; m < kShMaxBands; ++m) {
      double q = 1.0;
      for (int i = 1; i <= m; ++i) q *= -(2.0 * i - 1.0);
      q0[m] = q;
      for (int l = m; l < kShMaxBands; ++l) {
        double ratio = 1.0;  // (l - m)! / (l + m)!
        for (int i = l - m + 1; i <= l + m; ++i) ratio /= i;
        const double K = std::sqrt((2.0 * l + 1.0) / (4.0 * kPi) * ratio);
        k[l][m] = m == 0 ? K : std::sqrt(2.0) * K;
      }
    }
  }
};

// y[0 .. bands^2) for 1 <= bands <= kShMaxBands.
inline void sh_eval(const Vec3& w, int bands, double* y) {
  static const ShFactors f;
  double A[kShMaxBands], B[kShMaxBands];  // Re, Im of (x + i y)^m
  A[0] = 1.0;
  B[0] = 0.0;
  for (int m = 1; m < bands; ++m) {
    A[m] = A[m - 1] * w.x - B[m - 1] * w.y;
    B[m] = A[m - 1] * w.y + B[m - 1] * w.x;
  }
  for (int m = 0; m < bands; ++m) {
    // Q_l^m(z) = P_l^m(z) / (1 - z^2)^(m/2) for l = m, m+1, ...
    double q_prev = 0.0, q = f.q0[m];
    for (int l = m; l < bands; ++l) {
      if (l == m + 1) {
        q_prev = q;
        q = w.z * (2.0 * m + 1.0) * q;
      } else if (l > m + 1) {
        const double next = ((2.0 * l - 1.0) * w.z * q - (l + m - 1.0) * q_prev) / (l - m);
        q_prev = q;
        q = next;
      }
      if (m == 0) {
        y[l * l + l] = f.k[l][0] * q;
      } else {
        y[l * l + l + m] = f.k[l][m] * q * A[m];
        y[l * l + l - m] = f.k[l][m] * q * B[m];
      }
    }
  }
}

// Y_lm(w), l < bands, kept for a direction that many lookups share (a camera ray's -d along its march).
struct ShBasis {
  double y[kShMaxBands * kShMaxBands];
  ShBasis(const Vec3& w, int bands) { sh_eval(w, bands, y); }
};

// Y_lm of the axes x, y, z for l <= 1: the l = 1 band of a function, sum_m L_1m Y_1m(w), is a . w with
// a_i = sum_m L_1m Y_1m(e_i) (whatever the harmonics' sign convention).
struct ShAxes {
  double y[3][4];
  ShAxes() {
    for (int i = 0; i < 3; ++i) {
      Vec3 e(0.0);
      e[i] = 1.0;
      sh_eval(e, 2, y[i]);
    }
  }
};

// The bands l = 3 .. kShMaxBands - 1 of a function known by its moments Lc for l <= 2 (9 values), extrapolated
// from a lobe (ScatterGridSettings::lobe_tail): t[l], band l's value at the direction whose harmonics are y
// (t[0..2] = 0). The function about its l = 1 direction d, band by band f_l P_l(w . d), with
// f_l = (2l + 1) (f_1 / 3) r^(l - 1) and r = 3 f_2 / (5 f_1) from its bands 1 and 2 at d: exact for a constant
// plus c HG(r) about d (f_l = (2l + 1) c r^l / (4 pi)). Nothing where f_2 <= 0 (no lobe); r at most 0.95.
inline void sh_lobe_tail(const double* Lc, const double* y, double t[kShMaxBands]) {
  static const ShAxes axes;
  for (int l = 0; l < kShMaxBands; ++l) t[l] = 0.0;
  Vec3 a;
  for (int i = 0; i < 3; ++i) a[i] = Lc[1] * axes.y[i][1] + Lc[2] * axes.y[i][2] + Lc[3] * axes.y[i][3];
  const double f1 = a.length();
  if (!(f1 > 0.0)) return;
  double yd[9];
  sh_eval(a / f1, 3, yd);
  double f2 = 0.0;
  for (int h = 4; h < 9; ++h) f2 += Lc[h] * yd[h];
  const double r = std::min(0.95, 3.0 * f2 / (5.0 * f1));
  if (!(r > 0.0)) return;
  const double mu = std::clamp((Lc[1] * y[1] + Lc[2] * y[2] + Lc[3] * y[3]) / f1, -1.0, 1.0);
  double p_prev = mu, p = 0.5 * (3.0 * mu * mu - 1.0), rl = r * f1 / 3.0;  // P_1, P_2, (f_1 / 3) r^(l - 1)
  for (int l = 3; l < kShMaxBands; ++l) {
    const double next = ((2.0 * l - 1.0) * mu * p - (l - 1.0) * p_prev) / l;
    p_prev = p, p = next, rl *= r;
    t[l] = (2.0 * l + 1.0) * rl * p;
  }
}

}  // namespace nimbus
