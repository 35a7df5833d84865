// The paired comparison of two errors over the same items (core/analysis/paired_comparison.h):
// hand-computed cases, the degenerate ones, and its calibration: when both lists come from the
// same distribution the confidence must be about uniform (a 99% claim wrong about 1% of the time),
// and a real difference of a few standard errors must be detected.

#include "core/analysis/paired_comparison.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

namespace penumbra {
namespace {

TEST(PairedComparison, HandComputedCase) {
  std::vector<double> a = {1, 2, 3, 4};
  std::vector<double> b = {2, 2, 5, 5};  // differences 1, 0, 2, 1: mean 1, sd sqrt(2/3)
  PairedComparison c = compare_paired(a, b);
  EXPECT_EQ(c.items, 4);
  EXPECT_DOUBLE_EQ(c.mean_a, 2.5);
  EXPECT_DOUBLE_EQ(c.mean_b, 3.5);
  EXPECT_DOUBLE_EQ(c.difference_mean, 1.0);
  EXPECT_NEAR(c.difference_standard_error, std::sqrt(2.0 / 3.0) / 2.0, 1e-15);
  EXPECT_NEAR(c.z, 2.0 / std::sqrt(2.0 / 3.0), 1e-12);
  EXPECT_NEAR(c.confidence, standard_normal_cdf(c.z), 1e-15);
  EXPECT_DOUBLE_EQ(c.ratio(), 3.5 / 2.5);
}

TEST(PairedComparison, FactorScalesTheFirstList) {
  std::vector<double> a = {1, 2, 3};
  std::vector<double> b = {1.6, 3.1, 4.4};  // b - 1.5 a = 0.1, 0.1, -0.1
  PairedComparison c = compare_paired(a, b, 1.5);
  EXPECT_NEAR(c.difference_mean, 0.1 / 3.0, 1e-15);
  EXPECT_DOUBLE_EQ(c.factor, 1.5);
  EXPECT_GT(c.confidence, 0.5);
  EXPECT_LT(c.confidence, 0.9);
}

TEST(PairedComparison, ConstantDifferenceIsCertainAndEqualListsAreUndecided) {
  std::vector<double> a = {1, 5, 9};
  std::vector<double> b = {2, 6, 10};
  PairedComparison up = compare_paired(a, b);
  EXPECT_TRUE(std::isinf(up.z) && up.z > 0);
  EXPECT_EQ(up.confidence, 1.0);
  PairedComparison down = compare_paired(b, a);
  EXPECT_EQ(down.confidence, 0.0);
  PairedComparison same = compare_paired(a, a);
  EXPECT_EQ(same.z, 0.0);
  EXPECT_EQ(same.confidence, 0.5);
  std::vector<double> zeros = {0, 0};
  EXPECT_EQ(compare_paired(zeros, zeros).ratio(), 1.0);
  EXPECT_TRUE(std::isinf(compare_paired(zeros, std::vector<double>{0, 1}).ratio()));
}

TEST(PairedComparison, RefusesMismatchedOrEmptyLists) {
  std::vector<double> two = {1, 2}, three = {1, 2, 3}, none;
  EXPECT_THROW(compare_paired(two, three), std::invalid_argument);
  EXPECT_THROW(compare_paired(none, none), std::invalid_argument);
}

TEST(PairedComparison, NormalDistributionFunction) {
  EXPECT_DOUBLE_EQ(standard_normal_cdf(0), 0.5);
  EXPECT_NEAR(standard_normal_cdf(2.326347874), 0.99, 1e-9);
  EXPECT_NEAR(standard_normal_cdf(-1.959963985), 0.025, 1e-9);
  EXPECT_EQ(standard_normal_cdf(INFINITY), 1.0);
  EXPECT_EQ(standard_normal_cdf(-INFINITY), 0.0);
}

// Errors like the reproduction suite's: per-item squared errors whose scale varies a lot between
// items (shared by both lists), each a mean over a few trials.
std::vector<double> noisy_errors(std::mt19937_64& rng, const std::vector<double>& scales,
                                 double factor, int trials) {
  std::normal_distribution<double> normal;
  std::vector<double> out;
  for (double scale : scales) {
    double sum = 0;
    for (int t = 0; t < trials; ++t) {
      double e = normal(rng) * scale * std::sqrt(factor);
      sum += e * e;
    }
    out.push_back(sum / trials);
  }
  return out;
}

TEST(PairedComparison, ConfidenceIsCalibratedWhenThereIsNoDifference) {
  std::mt19937_64 rng(2012);
  std::lognormal_distribution<double> spread(0.0, 1.0);
  const int repetitions = 2000;
  int claimed_95 = 0, claimed_99 = 0;
  for (int r = 0; r < repetitions; ++r) {
    std::vector<double> scales(100);
    for (double& s : scales) s = spread(rng);
    std::vector<double> a = noisy_errors(rng, scales, 1.0, 16);
    std::vector<double> b = noisy_errors(rng, scales, 1.0, 16);
    PairedComparison c = compare_paired(a, b);
    claimed_95 += c.confidence >= 0.95;
    claimed_99 += c.confidence >= 0.99;
  }
  // Binomial(2000, 0.05): mean 100, sd 9.7; (2000, 0.01): mean 20, sd 4.5. Bounds at ~4 sd (the
  // normal approximation of a mean of 100 skewed items is slightly off in the tail, hence wider
  // than 3 sd).
  EXPECT_GT(claimed_95, 60);
  EXPECT_LT(claimed_95, 140);
  EXPECT_LT(claimed_99, 45);
}

TEST(PairedComparison, DetectsARealDifference) {
  // Item scales s with log s ~ N(0, 0.5^2): d_i = b_i - 1.5 a_i has mean 0.5 E[s^2] and a
  // relative spread of about sqrt(e - 1) = 1.3 around it, so z is about 0.5 sqrt(200) / 0.65 =
  // 11: every repetition must detect it.
  std::mt19937_64 rng(13);
  std::lognormal_distribution<double> spread(0.0, 0.5);
  int detected = 0;
  for (int r = 0; r < 200; ++r) {
    std::vector<double> scales(200);
    for (double& s : scales) s = spread(rng);
    std::vector<double> a = noisy_errors(rng, scales, 1.0, 64);
    std::vector<double> b = noisy_errors(rng, scales, 2.0, 64);  // twice the error
    PairedComparison c = compare_paired(a, b, 1.5);              // is b above 1.5 a?
    EXPECT_NEAR(c.ratio(), 2.0, 0.3);
    detected += c.confidence >= 0.99;
  }
  EXPECT_EQ(detected, 200);
}

}  // namespace
}  // namespace penumbra
