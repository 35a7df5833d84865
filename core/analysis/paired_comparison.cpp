// Paired comparison of two errors measured on the same items (paired_comparison.h).

#include "core/analysis/paired_comparison.h"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace penumbra {

double PairedComparison::ratio() const {
  if (mean_a > 0) return mean_b / mean_a;
  return mean_b > 0 ? std::numeric_limits<double>::infinity() : 1.0;
}

double standard_normal_cdf(double z) {
  if (std::isnan(z)) return 0.5;
  return 0.5 * std::erfc(-z / std::sqrt(2.0));
}

PairedComparison compare_paired(std::span<const double> a, std::span<const double> b,
                                double factor) {
  if (a.size() != b.size())
    throw std::invalid_argument("compare_paired: the two error lists differ in length");
  if (a.empty()) throw std::invalid_argument("compare_paired: no items to compare");
  PairedComparison result;
  result.items = int(a.size());
  result.factor = factor;
  const double n = double(a.size());

  // Means first, then the spread of the differences around their mean (two passes: the
  // differences can be tiny next to the errors themselves).
  double sum_a = 0, sum_b = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    sum_a += a[i];
    sum_b += b[i];
  }
  result.mean_a = sum_a / n;
  result.mean_b = sum_b / n;
  result.difference_mean = result.mean_b - factor * result.mean_a;

  if (a.size() >= 2) {
    double sum_squares = 0;
    for (size_t i = 0; i < a.size(); ++i) {
      double deviation = (b[i] - factor * a[i]) - result.difference_mean;
      sum_squares += deviation * deviation;
    }
    result.difference_standard_error = std::sqrt(sum_squares / (n - 1.0) / n);
  }

  if (result.difference_standard_error > 0) {
    result.z = result.difference_mean / result.difference_standard_error;
  } else if (result.difference_mean != 0) {
    // Every item differs by the same amount: the sign is certain.
    result.z = std::copysign(std::numeric_limits<double>::infinity(), result.difference_mean);
  }
  result.confidence = standard_normal_cdf(result.z);
  return result;
}

}  // namespace penumbra
