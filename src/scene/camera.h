// Pinhole camera: fov_y_deg is the full vertical field of view, image row 0 is the top, camera
// right = forward x up, one-pixel box filter.
#pragma once

#include <cmath>

#include "core/math.h"
#include "core/ray.h"
#include "nimbus/scene.h"

namespace nimbus {

class PinholeCamera {
 public:
  explicit PinholeCamera(const Camera& c) : origin_(c.position) {
    forward_ = normalize(c.look_at - c.position);
    right_ = normalize(cross(forward_, c.up));
    up_ = cross(right_, forward_);
    tan_half_ = std::tan(0.5 * c.fov_y_deg * kPi / 180.0);
    aspect_ = double(c.width) / c.height;
    width_ = c.width;
    height_ = c.height;
  }
  // Unit direction through image position (px, py) in pixels (px right, py down from the top).
  Vec3 direction(double px, double py) const {
    const double sx = (2.0 * px / width_ - 1.0) * tan_half_ * aspect_;
    const double sy = (1.0 - 2.0 * py / height_) * tan_half_;
    return normalize(forward_ + right_ * sx + up_ * sy);
  }
  const Vec3& origin() const { return origin_; }
  int width() const { return width_; }
  int height() const { return height_; }
  // The camera ray through image position (px, py).
  Ray generate_ray(double px, double py) const { return {origin_, direction(px, py)}; }

 private:
  Vec3 origin_, forward_, right_, up_;
  double tan_half_ = 1.0, aspect_ = 1.0;
  int width_ = 1, height_ = 1;
};

}  // namespace nimbus
