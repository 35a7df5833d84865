#pragma once
// Pinhole camera of SCENE_FORMAT.md: fov_y_deg is the full vertical angle; pixel (0,0) is the
// top-left corner of the image. pbrt-v3 cameras add a mirrored x axis, an explicit screen window
// and a crop of a larger frame (Camera in scene.h); without them the rays are the JSON camera's,
// bit for bit.

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
    if (camera.mirror_x) right_ = -right_;
    framed_ = camera.has_screen_window || camera.full_width > 0;
    if (framed_) {
      crop_x_ = camera.crop_x;
      crop_y_ = camera.crop_y;
      full_width_ = camera.full_width > 0 ? camera.full_width : camera.width;
      full_height_ = camera.full_height > 0 ? camera.full_height : camera.height;
      x0_ = camera.screen_x0;
      x1_ = camera.screen_x1;
      y0_ = camera.screen_y0;
      y1_ = camera.screen_y1;
    }
  }
  const Vec3& origin() const { return origin_; }
  // Unit direction through image position (px, py) in pixels (pixel centres at +0.5).
  Vec3 direction(double px, double py) const {
    if (framed_) {
      // pbrt-v3's raster-to-screen map: raster x runs from screen x0 to x1, raster y from y1
      // (top) to y0.
      double fx = (px + crop_x_) / full_width_, fy = (py + crop_y_) / full_height_;
      double sx = (x0_ + (x1_ - x0_) * fx) * tan_half_;
      double sy = (y1_ - (y1_ - y0_) * fy) * tan_half_;
      return normalize(forward_ + right_ * sx + up_ * sy);
    }
    double sx = (2.0 * px / width_ - 1.0) * tan_half_ * aspect_;
    double sy = (1.0 - 2.0 * py / height_) * tan_half_;
    return normalize(forward_ + right_ * sx + up_ * sy);
  }

 private:
  Vec3 origin_, forward_, right_, up_;
  double tan_half_ = 1, aspect_ = 1;
  int width_, height_;
  bool framed_ = false;
  double crop_x_ = 0, crop_y_ = 0, full_width_ = 1, full_height_ = 1;
  double x0_ = -1, x1_ = 1, y0_ = -1, y1_ = 1;
};

}  // namespace penumbra
