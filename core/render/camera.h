#pragma once
// Pinhole camera of SCENE_FORMAT.md: fov_y_deg is the full vertical angle; pixel (0,0) is the
// top-left corner of the image.

#include <cmath>

#include "core/math/vec.h"
#include "core/scene/scene.h"

namespace penumbra {

class CameraRays {
 public:
  explicit CameraRays(const Camera& camera)
      : origin_(camera.position), width_(camera.width), height_(camera.height) {
    forward_ = normalize(camera.look_at - camera.position);
    right_ = normalize(cross(forward_, camera.up));
    up_ = cross(right_, forward_);
    tan_half_ = std::tan(camera.fov_y_deg * kPi / 360.0);
    aspect_ = double(camera.width) / camera.height;
  }
  const Vec3& origin() const { return origin_; }
  // Unit direction through image position (px, py) in pixels (pixel centres at +0.5).
  Vec3 direction(double px, double py) const {
    double sx = (2.0 * px / width_ - 1.0) * tan_half_ * aspect_;
    double sy = (1.0 - 2.0 * py / height_) * tan_half_;
    return normalize(forward_ + right_ * sx + up_ * sy);
  }

 private:
  Vec3 origin_, forward_, right_, up_;
  double tan_half_ = 1, aspect_ = 1;
  int width_, height_;
};

}  // namespace penumbra
