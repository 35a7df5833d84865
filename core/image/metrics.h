#pragma once
// Error metrics against a reference (METHODS.md "Error metrics").

#include <map>
#include <span>
#include <string>

#include "core/image/image.h"
#include "core/scene/scene.h"

namespace penumbra {

inline constexpr double kMrseEpsilon = 1e-6;  // Salesin & Jarosz

// Mean over pixels and channels of (p - r)^2 / (r^2 + eps). Whole image, or one region
// (clipped to the image). Throws std::invalid_argument on size mismatch or an empty region.
double mrse(const Image& test, const Image& reference, double epsilon = kMrseEpsilon);
double mrse(const Image& test, const Image& reference, const Region& region,
            double epsilon = kMrseEpsilon);
double mse(const Image& test, const Image& reference);
double mse(const Image& test, const Image& reference, const Region& region);
double rmse(const Image& test, const Image& reference);

// Throws std::invalid_argument unless both images have the same size and full pixel buffers.
void check_same_size(const Image& test, const Image& reference);
// The region clipped to the image; throws std::invalid_argument when nothing is left.
Region clip_region(const Region& region, const Image& image);

struct ErrorSummary {
  double mrse = 0, mse = 0, rmse = 0;
};
// "image" for the whole image, then one entry per region.
std::map<std::string, ErrorSummary> error_summary(const Image& test, const Image& reference,
                                                  const std::map<std::string, Region>& regions);

// Least-squares slope of log(y) against log(x) (convergence rates). Needs >= 2 positive pairs.
double log_log_slope(std::span<const double> x, std::span<const double> y);

}  // namespace penumbra
