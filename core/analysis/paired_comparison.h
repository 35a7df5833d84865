#pragma once
// Is one estimator's error really larger than another's? A paired comparison over a set of items
// (penumbra pixels) on which both were measured: with a_i, b_i the two mean squared errors at
// item i and a factor c, the differences d_i = b_i - c a_i; their mean over the items, its
// standard error (sample standard deviation / sqrt(n)), z = mean / standard error and the
// one-sided normal confidence Phi(z) that mean(b) > c mean(a) holds for the population the items
// were drawn from. Pairing removes the variation between items that both errors share (a pixel
// with many discontinuities is hard for every pattern), so far fewer items are needed than when
// the two means are compared unpaired.
//
// Each b_i and a_i may itself be a noisy estimate (a mean over trials): that noise is part of the
// spread of d_i, so the confidence accounts for it too.

#include <span>

namespace penumbra {

struct PairedComparison {
  int items = 0;
  double mean_a = 0, mean_b = 0;
  double factor = 1;                     // c
  double difference_mean = 0;            // mean of d_i = b_i - c a_i
  double difference_standard_error = 0;  // of that mean; 0 with fewer than 2 items
  double z = 0;                          // difference_mean / standard error (+-inf if it is 0)
  double confidence = 0;                 // Phi(z): one-sided confidence that mean_b > c mean_a

  // mean_b / mean_a (+inf when mean_a is 0 and mean_b is not, 1 when both are 0).
  double ratio() const;
};

// Throws std::invalid_argument when the spans differ in length or are empty.
PairedComparison compare_paired(std::span<const double> a, std::span<const double> b,
                                double factor = 1.0);

// The standard normal distribution function Phi(z) = (1 + erf(z / sqrt 2)) / 2.
double standard_normal_cdf(double z);

}  // namespace penumbra
