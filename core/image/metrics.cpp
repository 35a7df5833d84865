// Error metrics against a reference (METHODS.md "Error metrics"). Sums are in double, per row
// first, so a 16k x 16k image loses no precision to a long running sum.

#include "core/image/metrics.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace penumbra {

void check_same_size(const Image& test, const Image& reference) {
  if (test.width != reference.width || test.height != reference.height)
    throw std::invalid_argument("image size mismatch: test is " + std::to_string(test.width) + "x" +
                                std::to_string(test.height) + ", reference is " +
                                std::to_string(reference.width) + "x" +
                                std::to_string(reference.height));
  size_t expected = size_t(test.width) * size_t(test.height) * 3;
  if (test.rgb.size() != expected || reference.rgb.size() != expected)
    throw std::invalid_argument("image pixel buffer does not hold width*height*3 floats");
}

Region clip_region(const Region& region, const Image& image) {
  Region clipped{std::max(region.x0, 0), std::max(region.y0, 0), std::min(region.x1, image.width),
                 std::min(region.y1, image.height)};
  if (clipped.x0 >= clipped.x1 || clipped.y0 >= clipped.y1)
    throw std::invalid_argument(
        "region [" + std::to_string(region.x0) + "," + std::to_string(region.x1) + ")x[" +
        std::to_string(region.y0) + "," + std::to_string(region.y1) + ") is empty inside the " +
        std::to_string(image.width) + "x" + std::to_string(image.height) + " image");
  return clipped;
}

namespace {

// Mean of error(p, r) over the pixels and channels of a (clipped, non-empty) region.
template <typename ChannelError>
double mean_over_region(const Image& test, const Image& reference, const Region& region,
                        ChannelError channel_error) {
  double total = 0;
  for (int y = region.y0; y < region.y1; ++y) {
    double row_total = 0;
    size_t begin = (size_t(y) * test.width + region.x0) * 3;
    size_t end = (size_t(y) * test.width + region.x1) * 3;
    for (size_t i = begin; i < end; ++i)
      row_total += channel_error(double(test.rgb[i]), double(reference.rgb[i]));
    total += row_total;
  }
  double count = double(region.x1 - region.x0) * double(region.y1 - region.y0) * 3.0;
  return total / count;
}

Region whole_image(const Image& image) {
  return Region{0, 0, image.width, image.height};
}

}  // namespace

double mrse(const Image& test, const Image& reference, const Region& region, double epsilon) {
  check_same_size(test, reference);
  Region clipped = clip_region(region, test);
  return mean_over_region(test, reference, clipped, [epsilon](double p, double r) {
    double difference = p - r;
    return difference * difference / (r * r + epsilon);
  });
}

double mrse(const Image& test, const Image& reference, double epsilon) {
  return mrse(test, reference, whole_image(test), epsilon);
}

double mse(const Image& test, const Image& reference, const Region& region) {
  check_same_size(test, reference);
  Region clipped = clip_region(region, test);
  return mean_over_region(test, reference, clipped, [](double p, double r) {
    double difference = p - r;
    return difference * difference;
  });
}

double mse(const Image& test, const Image& reference) {
  return mse(test, reference, whole_image(test));
}

double rmse(const Image& test, const Image& reference) {
  return std::sqrt(mse(test, reference));
}

std::map<std::string, ErrorSummary> error_summary(const Image& test, const Image& reference,
                                                  const std::map<std::string, Region>& regions) {
  auto summarize = [&](const Region& region) {
    ErrorSummary summary;
    summary.mrse = mrse(test, reference, region);
    summary.mse = mse(test, reference, region);
    summary.rmse = std::sqrt(summary.mse);
    return summary;
  };
  std::map<std::string, ErrorSummary> summaries;
  summaries["image"] = summarize(whole_image(test));
  for (const auto& [name, region] : regions) {
    try {
      summaries[name] = summarize(region);
    } catch (const std::invalid_argument& error) {
      throw std::invalid_argument("region '" + name + "': " + error.what());
    }
  }
  return summaries;
}

double log_log_slope(std::span<const double> x, std::span<const double> y) {
  if (x.size() != y.size())
    throw std::invalid_argument("log_log_slope: " + std::to_string(x.size()) + " x values but " +
                                std::to_string(y.size()) + " y values");
  // Keep the pairs where both logarithms exist.
  std::vector<double> log_x, log_y;
  for (size_t i = 0; i < x.size(); ++i) {
    if (!(x[i] > 0) || !(y[i] > 0) || !std::isfinite(x[i]) || !std::isfinite(y[i])) continue;
    log_x.push_back(std::log(x[i]));
    log_y.push_back(std::log(y[i]));
  }
  if (log_x.size() < 2)
    throw std::invalid_argument("log_log_slope needs at least 2 pairs with positive x and y, got " +
                                std::to_string(log_x.size()));
  // Least squares on centred values.
  double n = double(log_x.size());
  double mean_x = 0, mean_y = 0;
  for (size_t i = 0; i < log_x.size(); ++i) {
    mean_x += log_x[i];
    mean_y += log_y[i];
  }
  mean_x /= n;
  mean_y /= n;
  double sxx = 0, sxy = 0;
  for (size_t i = 0; i < log_x.size(); ++i) {
    sxx += (log_x[i] - mean_x) * (log_x[i] - mean_x);
    sxy += (log_x[i] - mean_x) * (log_y[i] - mean_y);
  }
  if (!(sxx > 0)) throw std::invalid_argument("log_log_slope: all x values are equal");
  return sxy / sxx;
}

}  // namespace penumbra
