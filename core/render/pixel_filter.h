#pragma once
// Filter importance sampling (Ernst et al. 2006): a camera sample's position in its pixel is
// drawn with density proportional to the pixel filter (Scene's PixelFilter: pbrt-v3's box,
// triangle and gaussian, all separable and non-negative), and every sample has weight one. The
// pixel's mean then converges to the filtered image pbrt-v3 computes by weighting splatted
// samples, while each pixel's estimate uses its own samples only, so tiles stay independent
// and merges exact.

#include <vector>

#include "core/math/vec.h"
#include "core/scene/scene.h"

namespace penumbra {

class PixelFilterSampler {
 public:
  explicit PixelFilterSampler(const PixelFilter& filter);

  // The position in pixel units relative to the pixel's top-left corner (in [0.5 - r, 0.5 + r])
  // of a sample with uniform numbers (ux, uy) in [0, 1)^2. The default box of radius 0.5 returns
  // (ux, uy) itself.
  Vec2 position(double ux, double uy) const {
    if (unit_box_) return {ux, uy};
    return {0.5 + sample_axis(ux, 0), 0.5 + sample_axis(uy, 1)};
  }

  // The normalized one-dimensional filter density along an axis (for tests).
  double density(double offset, int axis) const;

 private:
  double sample_axis(double u, int axis) const;
  double cdf(double x, int axis) const;  // unnormalized gaussian CDF from -radius

  PixelFilter filter_;
  bool unit_box_ = false;
  double radius_[2] = {0.5, 0.5};
  double gaussian_floor_[2] = {0, 0};  // exp(-alpha r^2)
  double gaussian_total_[2] = {1, 1};  // integral of the filter over [-r, r]
};

}  // namespace penumbra
