#include "core/render/pixel_filter.h"

#include <cmath>

namespace penumbra {

PixelFilterSampler::PixelFilterSampler(const PixelFilter& filter) : filter_(filter) {
  radius_[0] = filter.radius_x;
  radius_[1] = filter.radius_y;
  unit_box_ =
      filter.type == PixelFilterType::Box && filter.radius_x == 0.5 && filter.radius_y == 0.5;
  if (filter.type == PixelFilterType::Gaussian)
    for (int axis = 0; axis < 2; ++axis) {
      gaussian_floor_[axis] = std::exp(-filter.alpha * radius_[axis] * radius_[axis]);
      gaussian_total_[axis] = cdf(radius_[axis], axis);
    }
}

// Integral of exp(-alpha t^2) - exp(-alpha r^2) over [-r, x].
double PixelFilterSampler::cdf(double x, int axis) const {
  const double a = filter_.alpha, r = radius_[axis];
  const double s = std::sqrt(a);
  return 0.5 * std::sqrt(kPi / a) * (std::erf(s * x) + std::erf(s * r)) -
         gaussian_floor_[axis] * (x + r);
}

double PixelFilterSampler::density(double x, int axis) const {
  const double r = radius_[axis];
  if (!(std::abs(x) <= r)) return 0;
  switch (filter_.type) {
    case PixelFilterType::Box:
      return 1 / (2 * r);
    case PixelFilterType::Triangle:
      return (r - std::abs(x)) / (r * r);
    case PixelFilterType::Gaussian:
      return (std::exp(-filter_.alpha * x * x) - gaussian_floor_[axis]) / gaussian_total_[axis];
  }
  return 0;
}

double PixelFilterSampler::sample_axis(double u, int axis) const {
  const double r = radius_[axis];
  switch (filter_.type) {
    case PixelFilterType::Box:
      return (2 * u - 1) * r;
    case PixelFilterType::Triangle:
      // Inverse CDF of the tent r - |x| on [-r, r].
      return u < 0.5 ? -r + r * std::sqrt(2 * u) : r - r * std::sqrt(2 - 2 * u);
    case PixelFilterType::Gaussian: {
      // Invert the CDF: bisection keeps a bracket, Newton steps converge inside it.
      const double target = u * gaussian_total_[axis];
      double lo = -r, hi = r, x = 0;
      for (int iteration = 0; iteration < 100; ++iteration) {
        double f = cdf(x, axis) - target;
        if (f > 0)
          hi = x;
        else
          lo = x;
        double slope = std::exp(-filter_.alpha * x * x) - gaussian_floor_[axis];
        double next = slope > 0 ? x - f / slope : 0.5 * (lo + hi);
        if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
        if (std::abs(next - x) <= 1e-14 * r || hi - lo <= 1e-14 * r) return next;
        x = next;
      }
      return x;
    }
  }
  return 0;
}

}  // namespace penumbra
