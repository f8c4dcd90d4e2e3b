// The image-based environment light (docs/scene-format.md, "environment"): a lat-long (equirectangular)
// HDR map around the scene, oriented as Blender/Cycles map an Environment Texture (direction_to_
// equirectangular in Cycles' kernel/camera/projection.h):
//     u = 1/2 - atan2(y, x) / (2 pi)   (the image's centre looks along +x; u grows towards -y)
//     t = acos(z) / pi                  (t = 0: the top row, looking along +z; t = 1: the bottom, -z)
// in the map's own frame, which a rotation places in the world. The radiance is piecewise constant:
// the pixel a direction falls in, times `intensity` (Cycles' "Closest" interpolation).
//
// Importance sampling by luminance (pbrt-v4's piecewise-constant 2-D distribution, in our own words):
// pixel (i, j) is drawn with probability proportional to Y_ij sin(theta_j) (Y the Rec. 709 luminance,
// theta_j the polar angle of row j's centre; Y sin(theta_j) is exactly proportional to Y times the
// pixel's solid angle, since cos(a - h) - cos(a + h) = 2 sin(a) sin(h)): a marginal over rows, then a
// conditional within the row; within the pixel (u, t) is uniform. A density pdf_uv on the unit square
// is, per solid angle (dw = 2 pi^2 sin(theta) du dt),
//     pdf(w) = pdf_uv(u, t) / (2 pi^2 sin(theta)).
#pragma once

#include <array>
#include <vector>

#include "core/math.h"
#include "nimbus/transform.h"

namespace nimbus {

// (u, t) in [0, 1)^2 of a unit direction in the map's frame (formulas above), and back.
struct LatLong {
  double u = 0.0, t = 0.0;
};
LatLong direction_to_latlong(const Vec3& w);
Vec3 latlong_to_direction(double u, double t);

// A piecewise-constant density on [0, 1) with n cells of the given non-negative weights.
class PiecewiseConstant1D {
 public:
  explicit PiecewiseConstant1D(const std::vector<double>& weights);
  // x in [0, 1) with density pdf(x); *cell is the cell x falls in. total() must be > 0.
  double sample(double u, int* cell) const;
  double pdf(int cell) const { return total_ > 0.0 ? w_[cell] * double(w_.size()) / total_ : 0.0; }
  double total() const { return total_; }
  int size() const { return int(w_.size()); }

 private:
  std::vector<double> w_, cdf_;  // cdf_[k] = sum of w_[0 .. k) / total, cdf_[n] = 1
  double total_ = 0.0;
};

// A direction drawn towards the map: wi (world, from the shading point towards the map), the radiance
// arriving along it, and the density per solid angle it was drawn with (0: nothing drawn).
struct EnvSample {
  Vec3 wi;
  Rgb L{0.0};
  double pdf = 0.0;
};

class EnvMap {
 public:
  // rgb: width x height linear RGB (3 floats per pixel, row 0 the top), finite and >= 0;
  // world_from_map: a rotation; the radiance is intensity times the pixel.
  EnvMap(int width, int height, std::vector<float> rgb, const Transform& world_from_map, double intensity);

  // Radiance arriving from the world direction w (unit, pointing away from the scene towards the map).
  Rgb eval(const Vec3& w) const;
  // A direction with density proportional to luminance (u1: within the row, u2: the row).
  EnvSample sample(double u1, double u2) const;
  // The density per solid angle sample() draws the unit world direction w with.
  double pdf(const Vec3& w) const;
  // The real spherical-harmonic moments int L(w) Y_lm(w) dw of the world-space radiance, l < bands
  // (core/sh.h's basis and index l^2 + l + m), by `sub`^2 midpoint points per pixel.
  std::vector<Rgb> sh_moments(int bands, int sub = 4) const;
  // int Y(L(w)) dw over the sphere: the luminance "power" that photon emission shares by.
  double luminance_integral() const { return luminance_integral_; }

  int width() const { return width_; }
  int height() const { return height_; }
  Rgb pixel(int i, int j) const;  // times intensity
  const Transform& world_from_map() const { return world_from_map_; }

 private:
  int width_, height_;
  std::vector<float> rgb_;
  Transform world_from_map_, map_from_world_;
  double intensity_;
  std::vector<PiecewiseConstant1D> columns_;  // conditional within row j (built before rows_)
  PiecewiseConstant1D rows_;                  // marginal: row j's weight sum_i Y_ij sin(theta_j)
  double luminance_integral_ = 0.0;
  void pixel_of(const LatLong& ll, int* i, int* j) const;
};

}  // namespace nimbus
