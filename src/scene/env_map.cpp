// The image-based environment light (scene/env_map.h).
#include "scene/env_map.h"

#include <algorithm>
#include <cmath>

#include "core/check.h"
#include "core/sh.h"
#include "nimbus/error.h"

namespace nimbus {

LatLong direction_to_latlong(const Vec3& w) {
  LatLong ll;
  ll.u = 0.5 - std::atan2(w.y, w.x) / (2.0 * kPi);  // atan2 in [-pi, pi]: u in [0, 1]
  if (ll.u >= 1.0) ll.u -= 1.0;
  ll.t = std::acos(std::clamp(w.z, -1.0, 1.0)) / kPi;
  return ll;
}

Vec3 latlong_to_direction(double u, double t) {
  const double phi = kPi * (1.0 - 2.0 * u), theta = kPi * t;
  const double s = std::sin(theta);
  return {s * std::cos(phi), s * std::sin(phi), std::cos(theta)};
}

PiecewiseConstant1D::PiecewiseConstant1D(const std::vector<double>& weights) : w_(weights) {
  cdf_.assign(w_.size() + 1, 0.0);
  for (size_t k = 0; k < w_.size(); ++k) cdf_[k + 1] = cdf_[k] + w_[k];
  total_ = cdf_.back();
  if (total_ > 0.0)
    for (double& c : cdf_) c /= total_;
  cdf_.back() = 1.0;
}

double PiecewiseConstant1D::sample(double u, int* cell) const {
  NIMBUS_DCHECK(total_ > 0.0);
  // The last k with cdf_[k] <= u, skipping empty cells (their cdf steps are zero).
  const int n = int(w_.size());
  int k = int(std::upper_bound(cdf_.begin(), cdf_.end(), u) - cdf_.begin()) - 1;
  k = std::clamp(k, 0, n - 1);
  while (k > 0 && w_[k] <= 0.0) --k;  // only when u sits exactly on a step
  while (k < n - 1 && w_[k] <= 0.0) ++k;
  *cell = k;
  const double width = cdf_[k + 1] - cdf_[k];
  const double frac = width > 0.0 ? std::clamp((u - cdf_[k]) / width, 0.0, 1.0) : 0.5;
  return std::min((k + frac) / n, std::nextafter(1.0, 0.0));
}

namespace {

// Row j's weight and its pixels' luminance, with the sin(theta) of the row centre.
std::vector<double> row_luminance(const std::vector<float>& rgb, int width, int j) {
  std::vector<double> y(width);
  for (int i = 0; i < width; ++i) {
    const float* p = &rgb[(size_t(j) * width + i) * 3];
    y[i] = luminance(Rgb(p[0], p[1], p[2]));
  }
  return y;
}

PiecewiseConstant1D make_rows(const std::vector<float>& rgb, int width, int height,
                              std::vector<PiecewiseConstant1D>* columns) {
  std::vector<double> row_weight(height);
  for (int j = 0; j < height; ++j) {
    const double sin_theta = std::sin(kPi * (j + 0.5) / height);
    columns->emplace_back(row_luminance(rgb, width, j));
    row_weight[j] = columns->back().total() * sin_theta;
  }
  return PiecewiseConstant1D(row_weight);
}

}  // namespace

EnvMap::EnvMap(int width, int height, std::vector<float> rgb, const Transform& world_from_map,
               double intensity)
    : width_(width),
      height_(height),
      rgb_(std::move(rgb)),
      world_from_map_(world_from_map),
      map_from_world_(world_from_map.inverse()),
      intensity_(intensity),
      rows_(make_rows(rgb_, width_, height_, &columns_)) {
  if (rgb_.size() != size_t(width_) * height_ * 3)
    throw Error("environment map: pixel count does not match its size");
  // int Y dw = sum over pixels of Y times the pixel's solid angle (2 pi / W) (cos t0 - cos t1).
  for (int j = 0; j < height_; ++j) {
    const double solid =
        2.0 * kPi / width_ * (std::cos(kPi * j / height_) - std::cos(kPi * (j + 1) / height_));
    luminance_integral_ += intensity_ * columns_[j].total() * solid;
  }
}

Rgb EnvMap::pixel(int i, int j) const {
  const float* p = &rgb_[(size_t(j) * width_ + i) * 3];
  return Rgb(p[0], p[1], p[2]) * intensity_;
}

void EnvMap::pixel_of(const LatLong& ll, int* i, int* j) const {
  *i = std::clamp(int(ll.u * width_), 0, width_ - 1);
  *j = std::clamp(int(ll.t * height_), 0, height_ - 1);
}

Rgb EnvMap::eval(const Vec3& w) const {
  int i, j;
  pixel_of(direction_to_latlong(map_from_world_.vector(w)), &i, &j);
  return pixel(i, j);
}

EnvSample EnvMap::sample(double u1, double u2) const {
  EnvSample s;
  if (!(rows_.total() > 0.0)) return s;
  int i, j;
  const double t = rows_.sample(u2, &j);
  const double u = columns_[j].sample(u1, &i);
  const double sin_theta = std::sin(kPi * t);
  if (!(sin_theta > 0.0)) return s;
  const double pdf_uv = rows_.pdf(j) * columns_[j].pdf(i);
  s.pdf = pdf_uv / (2.0 * kPi * kPi * sin_theta);
  s.wi = world_from_map_.vector(latlong_to_direction(u, t));
  s.L = pixel(i, j);
  return s;
}

double EnvMap::pdf(const Vec3& w) const {
  if (!(rows_.total() > 0.0)) return 0.0;
  const Vec3 wm = map_from_world_.vector(w);
  const double sin_theta = std::hypot(wm.x, wm.y);  // precise near the poles
  if (!(sin_theta > 0.0)) return 0.0;
  int i, j;
  pixel_of(direction_to_latlong(wm), &i, &j);
  return rows_.pdf(j) * columns_[j].pdf(i) / (2.0 * kPi * kPi * sin_theta);
}

std::vector<Rgb> EnvMap::sh_moments(int bands, int sub) const {
  bands = std::clamp(bands, 1, kShMaxBands);
  std::vector<Rgb> m(size_t(bands) * bands, Rgb(0.0));
  double y[kShMaxBands * kShMaxBands];
  const double du = 1.0 / (double(width_) * sub), dt = 1.0 / (double(height_) * sub);
  for (int j = 0; j < height_ * sub; ++j) {
    const double t = (j + 0.5) * dt;
    // The sub-pixel's solid angle: 2 pi du (cos t0 - cos t1) in units of the unit square.
    const double solid = 2.0 * kPi * du * (std::cos(kPi * j * dt) - std::cos(kPi * (j + 1) * dt));
    for (int i = 0; i < width_ * sub; ++i) {
      const Rgb L = pixel(i / sub, j / sub);
      if (max_component(L) <= 0.0) continue;
      sh_eval(world_from_map_.vector(latlong_to_direction((i + 0.5) * du, t)), bands, y);
      for (int h = 0; h < bands * bands; ++h) m[h] += L * (y[h] * solid);
    }
  }
  return m;
}

}  // namespace nimbus
