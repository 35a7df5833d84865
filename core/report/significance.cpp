// Student's t distribution through the regularized incomplete beta function (its continued
// fraction, evaluated with the modified Lentz method), intervals and paired differences.

#include "core/report/significance.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace penumbra {

namespace {

// The continued fraction of I_x(a, b) (valid and fast for x < (a + 1) / (a + b + 2)).
double incomplete_beta_fraction(double a, double b, double x) {
  constexpr double kTiny = 1e-300;
  double c = 1, d = 1 - (a + b) * x / (a + 1);
  if (std::abs(d) < kTiny) d = kTiny;
  d = 1 / d;
  double fraction = d;
  for (int m = 1; m <= 500; ++m) {
    // Even step.
    double numerator = m * (b - m) * x / ((a + 2 * m - 1) * (a + 2 * m));
    d = 1 + numerator * d;
    if (std::abs(d) < kTiny) d = kTiny;
    c = 1 + numerator / c;
    if (std::abs(c) < kTiny) c = kTiny;
    d = 1 / d;
    fraction *= d * c;
    // Odd step.
    numerator = -(a + m) * (a + b + m) * x / ((a + 2 * m) * (a + 2 * m + 1));
    d = 1 + numerator * d;
    if (std::abs(d) < kTiny) d = kTiny;
    c = 1 + numerator / c;
    if (std::abs(c) < kTiny) c = kTiny;
    d = 1 / d;
    const double step = d * c;
    fraction *= step;
    if (std::abs(step - 1) < 1e-15) break;
  }
  return fraction;
}

// The regularized incomplete beta function I_x(a, b), x in [0, 1].
double regularized_incomplete_beta(double a, double b, double x) {
  if (x <= 0) return 0;
  if (x >= 1) return 1;
  const double log_front =
      std::lgamma(a + b) - std::lgamma(a) - std::lgamma(b) + a * std::log(x) + b * std::log1p(-x);
  const double front = std::exp(log_front);
  if (x < (a + 1) / (a + b + 2)) return front * incomplete_beta_fraction(a, b, x) / a;
  return 1 - front * incomplete_beta_fraction(b, a, 1 - x) / b;
}

}  // namespace

double student_t_cdf(double t, double dof) {
  if (!(dof > 0)) throw std::invalid_argument("student_t_cdf: degrees of freedom must be > 0");
  if (std::isnan(t)) throw std::invalid_argument("student_t_cdf: t is NaN");
  if (std::isinf(t)) return t > 0 ? 1.0 : 0.0;
  const double tail = 0.5 * regularized_incomplete_beta(dof / 2, 0.5, dof / (dof + t * t));
  return t > 0 ? 1 - tail : tail;
}

double student_t_quantile(double p, double dof) {
  if (!(p > 0 && p < 1)) throw std::invalid_argument("student_t_quantile: p must be in (0, 1)");
  if (!(dof > 0)) throw std::invalid_argument("student_t_quantile: degrees of freedom must be > 0");
  if (p < 0.5) return -student_t_quantile(1 - p, dof);
  // Bisection on [0, hi]: the cdf is increasing; hi grows until it brackets p.
  double lo = 0, hi = 1;
  while (student_t_cdf(hi, dof) < p && hi < 1e300) hi *= 2;
  for (int i = 0; i < 200 && hi - lo > 1e-14 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    if (student_t_cdf(mid, dof) < p)
      lo = mid;
    else
      hi = mid;
  }
  return 0.5 * (lo + hi);
}

MeanInterval mean_interval(std::span<const double> values, double common_deviation, double level) {
  MeanInterval result;
  result.count = int(values.size());
  if (values.empty()) return result;
  double sum = 0;
  for (double v : values) sum += v;
  result.mean = sum / double(values.size());
  if (values.size() < 2) return result;
  double squares = 0;
  for (double v : values) squares += (v - result.mean) * (v - result.mean);
  const double k = double(values.size());
  result.std = std::sqrt(squares / (k - 1));
  const double own = result.std / std::sqrt(k);  // standard error of the mean from the spread
  const double p = 0.5 + level / 2;
  // Each part's half-width at its own quantile, added in quadrature (see the header).
  const double own_half = own > 0 ? student_t_quantile(p, k - 1) * own : 0.0;
  const double common_half = student_t_quantile(p, 1e7) * common_deviation;
  result.has_interval = true;
  result.half_width = std::sqrt(own_half * own_half + common_half * common_half);
  return result;
}

PairedDifference paired_difference(std::span<const double> a, std::span<const double> b,
                                   double level) {
  if (a.size() != b.size())
    throw std::invalid_argument("paired_difference: " + std::to_string(a.size()) +
                                " values against " + std::to_string(b.size()));
  PairedDifference result;
  result.pairs = int(a.size());
  if (a.empty()) return result;
  std::vector<double> differences(a.size());
  for (size_t i = 0; i < a.size(); ++i) differences[i] = a[i] - b[i];
  const MeanInterval interval = mean_interval(differences, 0, level);
  result.difference = interval.mean;
  if (!interval.has_interval) return result;
  result.half_width = interval.half_width;
  const double standard_error = interval.std / std::sqrt(double(a.size()));
  if (standard_error > 0) {
    const double t = std::abs(interval.mean) / standard_error;
    result.p_value = 2 * (1 - student_t_cdf(t, double(a.size() - 1)));
  } else {
    result.p_value = interval.mean != 0 ? 0.0 : 1.0;
  }
  if (result.p_value < 1 - level) result.sign = interval.mean > 0 ? 1 : -1;
  return result;
}

}  // namespace penumbra
