#pragma once
// Goodness-of-fit helpers shared by the sampling tests.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <vector>

namespace penumbra::testing {

// Kolmogorov-Smirnov statistic D of a sample against the uniform distribution on [0,1).
inline double ks_statistic_uniform(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  double n = static_cast<double>(values.size());
  double d = 0.0;
  for (size_t i = 0; i < values.size(); ++i) {
    double below = static_cast<double>(i) / n;
    double above = static_cast<double>(i + 1) / n;
    d = std::max({d, above - values[i], values[i] - below});
  }
  return d;
}

// The asymptotic KS critical value at significance 0.001: sqrt(-ln(0.001/2) / 2) / sqrt(n)
// = 1.9495 / sqrt(n) (Smirnov's limit distribution; accurate for n in the thousands).
inline double ks_critical_0001(size_t n) {
  return std::sqrt(-std::log(0.0005) / 2.0) / std::sqrt(static_cast<double>(n));
}

// Pearson's chi-square of observed counts against equal expected counts.
inline double chi_square_equal(const std::vector<uint64_t>& counts) {
  double total = static_cast<double>(std::accumulate(counts.begin(), counts.end(), uint64_t{0}));
  double expected = total / static_cast<double>(counts.size());
  double chi2 = 0.0;
  for (uint64_t c : counts) {
    double d = static_cast<double>(c) - expected;
    chi2 += d * d / expected;
  }
  return chi2;
}

// The chi-square critical value at significance 0.001 for `dof` degrees of freedom, by the
// Wilson-Hilferty cube approximation (z = 3.0902 for 0.999); within 1% for dof >= 10.
inline double chi_square_critical_0001(double dof) {
  double z = 3.0902;
  double c = 2.0 / (9.0 * dof);
  double root = 1.0 - c + z * std::sqrt(c);
  return dof * root * root * root;
}

// Pearson's correlation coefficient of two equally long series.
inline double correlation(const std::vector<double>& a, const std::vector<double>& b) {
  double n = static_cast<double>(a.size());
  double mean_a = std::accumulate(a.begin(), a.end(), 0.0) / n;
  double mean_b = std::accumulate(b.begin(), b.end(), 0.0) / n;
  double cov = 0.0, var_a = 0.0, var_b = 0.0;
  for (size_t i = 0; i < a.size(); ++i) {
    cov += (a[i] - mean_a) * (b[i] - mean_b);
    var_a += (a[i] - mean_a) * (a[i] - mean_a);
    var_b += (b[i] - mean_b) * (b[i] - mean_b);
  }
  return cov / std::sqrt(var_a * var_b);
}

}  // namespace penumbra::testing
