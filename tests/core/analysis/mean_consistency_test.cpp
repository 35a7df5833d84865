// The stability table's consistency test (core/analysis/mean_consistency.h): its false-alarm rate
// is the one asked for at every trial count (measured over simulated unbiased estimators), where
// a fixed 5-standard-error threshold is not; with a reference of its own noise too (Welch); a
// real bias is found.
#include "core/analysis/mean_consistency.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>

namespace penumbra {
namespace {

struct Sample {
  double mean = 0, standard_error = 0;
};

Sample draw(std::mt19937_64& random, int n, double mu, double sigma) {
  std::normal_distribution<double> normal(mu, sigma);
  double sum = 0, squares = 0;
  std::vector<double> values(n);
  for (double& value : values) {
    value = normal(random);
    sum += value;
  }
  const double mean = sum / n;
  for (double value : values) squares += (value - mean) * (value - mean);
  return {mean, std::sqrt(squares / (n - 1) / n)};
}

// At a rate of 1% (so that 20000 repetitions measure it: its standard error is 0.07%).
TEST(MeanConsistency, FalseAlarmRateHoldsAtEveryTrialCount) {
  std::mt19937_64 random(2024);
  const int repetitions = 20000;
  const double rate = 0.01;
  const double bound = 4 * std::sqrt(rate * (1 - rate) / repetitions);  // 0.28%
  for (int trials : {4, 16, 256}) {
    int alarms = 0, naive_alarms = 0;
    const double naive_threshold = 2.5758293035489;  // the normal quantile of the same rate
    for (int r = 0; r < repetitions; ++r) {
      Sample s = draw(random, trials, 3.0, 2.0);
      MeanConsistency test = mean_consistency(s.mean, s.standard_error, trials, 3.0, 0, 0, rate);
      alarms += !test.consistent;
      naive_alarms += std::abs(s.mean - 3.0) / s.standard_error > naive_threshold;
    }
    const double measured = double(alarms) / repetitions;
    EXPECT_NEAR(measured, rate, bound) << trials << " trials";
    if (trials <= 16) {
      EXPECT_GT(double(naive_alarms) / repetitions, rate + 2 * bound)
          << "a fixed threshold holds its rate at " << trials << " trials?";
    }
  }
}

TEST(MeanConsistency, NoisyReferenceUsesWelchDegreesOfFreedom) {
  std::mt19937_64 random(7);
  const int repetitions = 20000;
  const double rate = 0.01;
  int alarms = 0;
  for (int r = 0; r < repetitions; ++r) {
    Sample s = draw(random, 8, 1.0, 1.0);
    Sample ref = draw(random, 12, 1.0, 3.0);
    alarms += !mean_consistency(s.mean, s.standard_error, 8, ref.mean, ref.standard_error, 12, rate)
                   .consistent;
  }
  EXPECT_NEAR(double(alarms) / repetitions, rate, 4 * std::sqrt(rate * (1 - rate) / repetitions));
  // The degrees of freedom lie between the smaller sample's and the sum's.
  MeanConsistency test = mean_consistency(1.0, 0.3, 8, 1.0, 0.8, 12);
  EXPECT_GT(test.dof, 7.0);
  EXPECT_LT(test.dof, 18.0);
}

TEST(MeanConsistency, ThresholdsAndABiasFound) {
  // Many trials: the 5-sigma rate is 5 standard errors; 16 trials need 8.27 (t with 15 degrees of
  // freedom, checked by numerical integration of its density).
  EXPECT_NEAR(mean_consistency(0, 1, 1 << 20, 0, 0, 0).threshold, 5.0, 1e-3);
  const double sixteen = mean_consistency(0, 1, 16, 0, 0, 0).threshold;
  EXPECT_NEAR(sixteen, 8.2671, 1e-3);
  // A bias of 20 standard errors over 256 trials is found; 6 over 16 trials is noise.
  EXPECT_FALSE(mean_consistency(1.2, 0.01, 256, 1.0, 0, 0).consistent);
  EXPECT_TRUE(mean_consistency(1.06, 0.01, 16, 1.0, 0, 0).consistent);
  EXPECT_FALSE(mean_consistency(1.06, 0.01, 256, 1.0, 0, 0).consistent);
  // Exact agreement with no spread; any difference with no spread.
  EXPECT_TRUE(mean_consistency(2, 0, 16, 2, 0, 0).consistent);
  EXPECT_FALSE(mean_consistency(2.1, 0, 16, 2, 0, 0).consistent);
  EXPECT_THROW(mean_consistency(0, 1, 1, 0, 0, 0), std::invalid_argument);
  EXPECT_THROW(mean_consistency(0, 1, 8, 0, 0, 0, 0.0), std::invalid_argument);
}

}  // namespace
}  // namespace penumbra
