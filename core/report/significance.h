#pragma once
// Confidence intervals and paired comparisons over a batch's repeats.
//
// A batch runs every method k times with independent seeds (repeat r uses seed + r for every
// method, so the methods' repeat r share their camera jitter: runs are paired by repeat). A
// table cell is the mean of the k values with a 95% Student t interval. When every run shares a
// source of error of known standard deviation u (the reference's realised noise,
// core/image/noise_corrected_mrse.h), it widens the interval: half-width
// sqrt((t_{k-1} s / sqrt k)^2 + (z u)^2), each part at its own quantile (t with k - 1 degrees of
// freedom for the repeats' standard deviation s, the normal z for the known u), added in
// quadrature. That is exact when either part is alone and conservative when both matter:
// measured over 2000 synthetic batches of k = 3 (tests/core/report/significance_test.cpp),
// 94.9-95.3% with a clean reference, 96.1-96.7% where the reference's noise dominates,
// 96.8-97.3% where it is about a third of the variance (three sets of batches each).
// (Welch-Satterthwaite's effective degrees of freedom undercover there, 92.3-93.3%, and so does
// plugging the estimated ratio of the parts into the exact coverage, 91.5-92.8%: at k = 3 the ratio
// cannot be estimated.)
//
// Whether method A beats B in a region: the paired differences a_r - b_r over the repeats, their
// mean and a two-sided 95% t interval (k - 1 degrees of freedom); A beats B when the interval
// lies below zero. The reference's common noise is the same number in a_r and b_r and cancels.

#include <span>
#include <vector>

namespace penumbra {

// Student's t distribution with `dof` > 0 degrees of freedom (need not be an integer).
double student_t_cdf(double t, double dof);
// The p-quantile, p in (0, 1).
double student_t_quantile(double p, double dof);

struct MeanInterval {
  int count = 0;
  double mean = 0;
  double std = 0;             // sample standard deviation of the values (0 for one value)
  double half_width = 0;      // of the interval mean +- half_width, when has_interval
  bool has_interval = false;  // needs two or more values
  double lower() const { return mean - half_width; }
  double upper() const { return mean + half_width; }
};

// The mean of `values` with its `level` interval (two or more values); `common_deviation` is
// the standard deviation of an error every value shares. Empty values: count 0, no interval.
MeanInterval mean_interval(std::span<const double> values, double common_deviation = 0,
                           double level = 0.95);

struct PairedDifference {
  int pairs = 0;
  double difference = 0;  // mean of a_r - b_r
  double half_width = 0;  // of its two-sided interval (when pairs >= 2)
  double p_value = 1;     // two-sided, of "no difference"
  // +1: a is significantly larger than b; -1: significantly smaller; 0: not significant (or
  // fewer than two pairs).
  int sign = 0;
};

// Throws std::invalid_argument when the spans differ in length.
PairedDifference paired_difference(std::span<const double> a, std::span<const double> b,
                                   double level = 0.95);

}  // namespace penumbra
