// MRSE with the reference's noise removed (the derivation is in the header). Sums in double, per
// row first, like core/image/metrics.cpp.

#include "core/image/noise_corrected_mrse.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace penumbra {

namespace {

void check_sizes(const Image& test, const Image& reference, const Image& variance) {
  check_same_size(test, reference);
  if (variance.width == 0 && variance.height == 0) return;
  if (variance.width != reference.width || variance.height != reference.height ||
      variance.rgb.size() != reference.rgb.size())
    throw std::invalid_argument("reference variance is " + std::to_string(variance.width) + "x" +
                                std::to_string(variance.height) + ", the reference is " +
                                std::to_string(reference.width) + "x" +
                                std::to_string(reference.height));
}

double checked_variance(const Image& variance, size_t index, int x, int y) {
  const double value = variance.rgb[index];
  if (!std::isfinite(value) || value < 0)
    throw std::invalid_argument("reference variance at pixel (" + std::to_string(x) + ", " +
                                std::to_string(y) + ") is " + std::to_string(value) +
                                " (must be finite and non-negative)");
  return value;
}

}  // namespace

double NoiseCorrectedError::reference_share() const {
  return plain > 0 ? reference_term / plain : 0.0;
}

NoiseCorrectedError noise_corrected_mrse(const Image& test, const Image& reference,
                                         const Image& reference_variance, const Region& region,
                                         double epsilon) {
  check_sizes(test, reference, reference_variance);
  const Region area = clip_region(region, test);
  const bool has_variance = reference_variance.width > 0;
  double plain = 0, term = 0, deviation_squares = 0;
  for (int y = area.y0; y < area.y1; ++y) {
    double row_plain = 0, row_term = 0, row_squares = 0;
    for (int x = area.x0; x < area.x1; ++x) {
      // Per pixel, the channels' deviations add (they share the pixel's samples).
      double pixel_deviation = 0;
      for (int c = 0; c < 3; ++c) {
        const size_t i = (size_t(y) * test.width + x) * 3 + c;
        const double r = reference.rgb[i];
        const double difference = double(test.rgb[i]) - r;
        const double weight = 1.0 / (r * r + epsilon);
        row_plain += difference * difference * weight;
        if (!has_variance) continue;
        const double s2 = checked_variance(reference_variance, i, x, y);
        row_term += s2 * weight;
        pixel_deviation += std::sqrt(2.0) * s2 * weight;
      }
      row_squares += pixel_deviation * pixel_deviation;
    }
    plain += row_plain;
    term += row_term;
    deviation_squares += row_squares;
  }
  const double count = double(area.x1 - area.x0) * double(area.y1 - area.y0) * 3.0;
  NoiseCorrectedError error;
  error.has_variance = has_variance;
  error.plain = plain / count;
  error.reference_term = term / count;
  error.corrected = error.plain - error.reference_term;
  error.reference_deviation = std::sqrt(deviation_squares) / count;
  return error;
}

NoiseCorrectedError noise_corrected_mrse(const Image& test, const Image& reference,
                                         const Image& reference_variance, double epsilon) {
  return noise_corrected_mrse(test, reference, reference_variance,
                              Region{0, 0, test.width, test.height}, epsilon);
}

std::map<std::string, NoiseCorrectedError> noise_corrected_summary(
    const Image& test, const Image& reference, const Image& reference_variance,
    const std::map<std::string, Region>& regions) {
  std::map<std::string, NoiseCorrectedError> summaries;
  summaries["image"] = noise_corrected_mrse(test, reference, reference_variance);
  for (const auto& [name, region] : regions) {
    try {
      summaries[name] = noise_corrected_mrse(test, reference, reference_variance, region);
    } catch (const std::invalid_argument& error) {
      throw std::invalid_argument("region '" + name + "': " + error.what());
    }
  }
  return summaries;
}

double reference_noise_mrse(const Image& reference, const Image& reference_variance,
                            const Region& region, double epsilon) {
  return noise_corrected_mrse(reference, reference, reference_variance, region, epsilon)
      .reference_term;
}

double noise_per_sample(const Image& variance, uint32_t spp, const Image& denominator,
                        const Region& region, double epsilon) {
  // The variance takes the reference's place in noise_corrected_mrse's reference term.
  if (variance.width == 0) throw std::invalid_argument("noise per sample: no variance layer");
  return double(spp) * reference_noise_mrse(denominator, variance, region, epsilon);
}

}  // namespace penumbra
