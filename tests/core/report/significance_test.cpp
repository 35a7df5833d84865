// Intervals and paired comparisons: Student t quantiles against tabulated values, the coverage of
// the 95% interval of a batch cell over many synthetic batches (k = 3 repeats of a synthetic
// render against one shared noisy reference, the corrected MRSE of core/image), and the paired
// comparison's power and false-positive rate.

#include "core/report/significance.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "core/image/noise_corrected_mrse.h"

namespace penumbra {
namespace {

TEST(StudentT, QuantilesMatchTables) {
  // Two-sided 95%: t_{0.975}.
  EXPECT_NEAR(student_t_quantile(0.975, 1), 12.706204736, 1e-7);
  EXPECT_NEAR(student_t_quantile(0.975, 2), 4.302652730, 1e-8);
  EXPECT_NEAR(student_t_quantile(0.975, 4), 2.776445105, 1e-8);
  EXPECT_NEAR(student_t_quantile(0.975, 10), 2.228138852, 1e-8);
  EXPECT_NEAR(student_t_quantile(0.975, 1e7), 1.959963985, 1e-6);
  EXPECT_NEAR(student_t_quantile(0.995, 5), 4.032142984, 1e-8);
  EXPECT_NEAR(student_t_quantile(0.025, 2), -4.302652730, 1e-8);
  EXPECT_NEAR(student_t_cdf(0, 3), 0.5, 1e-15);
  EXPECT_NEAR(student_t_cdf(2.0, 3) + student_t_cdf(-2.0, 3), 1.0, 1e-14);
  // Non-integer degrees of freedom (Welch): between its neighbours.
  const double t25 = student_t_quantile(0.975, 2.5);
  EXPECT_LT(t25, student_t_quantile(0.975, 2));
  EXPECT_GT(t25, student_t_quantile(0.975, 3));
  EXPECT_THROW(student_t_quantile(1.0, 2), std::invalid_argument);
  EXPECT_THROW(student_t_cdf(1.0, 0), std::invalid_argument);
}

TEST(MeanInterval, SmallCases) {
  std::vector<double> none;
  EXPECT_EQ(mean_interval(none).count, 0);
  std::vector<double> one{2.5};
  MeanInterval single = mean_interval(one);
  EXPECT_EQ(single.mean, 2.5);
  EXPECT_FALSE(single.has_interval);
  std::vector<double> three{1, 2, 3};
  MeanInterval interval = mean_interval(three);
  EXPECT_TRUE(interval.has_interval);
  EXPECT_DOUBLE_EQ(interval.mean, 2);
  EXPECT_DOUBLE_EQ(interval.std, 1);
  EXPECT_NEAR(interval.half_width, 4.302652730 / std::sqrt(3.0), 1e-8);
  // A shared error only: the normal quantile.
  std::vector<double> same{4, 4, 4};
  EXPECT_NEAR(mean_interval(same, 0.5).half_width, 1.959963985 * 0.5, 1e-6);
  EXPECT_EQ(mean_interval(same).half_width, 0.0);
}

// Synthetic renders: a truth mu per pixel channel, repeats mu + N(0, (a mu)^2), one reference
// per batch mu + N(0, (b mu)^2) with its sample variance of n = 256 samples as variance layer;
// the three channels of a pixel move together.
struct SyntheticBatch {
  int width = 24, height = 16;
  std::vector<double> mu;
  explicit SyntheticBatch(uint32_t seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> value(0.05, 3.0);
    mu.resize(size_t(width) * height * 3);
    for (double& m : mu) m = value(rng);
  }
  double true_mrse(double relative) const {
    double sum = 0;
    for (double m : mu) sum += (relative * m) * (relative * m) / (m * m + kMrseEpsilon);
    return sum / double(mu.size());
  }
  Image noisy(std::mt19937_64& rng, double relative, Image* variance = nullptr) const {
    std::normal_distribution<double> normal;
    std::chi_squared_distribution<double> chi2(255);
    Image image(width, height);
    if (variance) *variance = Image(width, height);
    // The channels of a pixel share its samples (as in a render): one draw per pixel.
    for (size_t pixel = 0; pixel < mu.size() / 3; ++pixel) {
      const double z = normal(rng), spread = chi2(rng) / 255;
      for (size_t i = 3 * pixel; i < 3 * pixel + 3; ++i) {
        const double sigma = relative * mu[i];
        image.rgb[i] = float(mu[i] + sigma * z);
        if (variance) variance->rgb[i] = float(sigma * sigma * spread);
      }
    }
    return image;
  }
};

double coverage(double test_relative, double reference_relative, int repeats, int batches) {
  SyntheticBatch synthetic(21);
  const double truth = synthetic.true_mrse(test_relative);
  std::mt19937_64 rng(uint64_t(1000 * test_relative + 7 * repeats));
  int covered = 0;
  for (int b = 0; b < batches; ++b) {
    Image variance;
    const Image reference = synthetic.noisy(rng, reference_relative, &variance);
    std::vector<double> values;
    double deviation = 0;
    for (int r = 0; r < repeats; ++r) {
      NoiseCorrectedError error =
          noise_corrected_mrse(synthetic.noisy(rng, test_relative), reference, variance);
      values.push_back(error.corrected);
      deviation = error.reference_deviation;  // the reference's: the same for every repeat
    }
    MeanInterval interval = mean_interval(values, deviation);
    if (interval.lower() <= truth && truth <= interval.upper()) ++covered;
  }
  return double(covered) / batches;
}

TEST(MeanInterval, CoverageOfThe95PercentIntervalOverSyntheticBatches) {
  // 2000 batches: the coverage's standard error is 0.49%, so 93-97% is four of them either side.
  // A clean reference (its noise 1% of the plain MRSE): the repeats' spread alone.
  const double own = coverage(0.04, 0.004, 3, 2000);
  std::printf("coverage with a clean reference: %.4f\n", own);
  EXPECT_GE(own, 0.93);
  EXPECT_LE(own, 0.97);
  // A noisy reference and a clean method: the reference's shared error dominates the interval.
  const double shared = coverage(0.01, 0.03, 3, 2000);
  std::printf("coverage where the reference's noise dominates: %.4f\n", shared);
  EXPECT_GE(shared, 0.93);
  EXPECT_LE(shared, 0.97);
  // Both parts (the reference's a third of the variance): conservative, never below 95%.
  const double mixed = coverage(0.04, 0.028, 3, 2000);
  std::printf("coverage with both parts: %.4f\n", mixed);
  EXPECT_GE(mixed, 0.945);
  EXPECT_LE(mixed, 0.98);
  // Without the reference's deviation an interval against a reference whose noise is most of
  // the plain MRSE undercovers: the deviation is needed.
  SyntheticBatch synthetic(21);
  const double truth = synthetic.true_mrse(0.04);
  std::mt19937_64 rng(99);
  int covered = 0;
  for (int b = 0; b < 1000; ++b) {
    Image variance;
    const Image reference = synthetic.noisy(rng, 0.06, &variance);
    std::vector<double> values;
    for (int r = 0; r < 3; ++r)
      values.push_back(
          noise_corrected_mrse(synthetic.noisy(rng, 0.04), reference, variance).corrected);
    MeanInterval interval = mean_interval(values);
    if (interval.lower() <= truth && truth <= interval.upper()) ++covered;
  }
  std::printf("coverage without the reference's deviation: %.4f\n", covered / 1000.0);
  EXPECT_LT(covered / 1000.0, 0.9);
}

TEST(PairedDifference, FindsTheBetterMethodAndRarelyAWinnerBetweenEqualOnes) {
  SyntheticBatch synthetic(5);
  std::mt19937_64 rng(17);
  int found = 0, false_positives = 0;
  const int batches = 1000;
  for (int b = 0; b < batches; ++b) {
    Image variance;
    const Image reference = synthetic.noisy(rng, 0.02, &variance);
    std::vector<double> better, worse, same;
    for (int r = 0; r < 3; ++r) {
      better.push_back(
          noise_corrected_mrse(synthetic.noisy(rng, 0.030), reference, variance).corrected);
      worse.push_back(
          noise_corrected_mrse(synthetic.noisy(rng, 0.042), reference, variance).corrected);
      same.push_back(
          noise_corrected_mrse(synthetic.noisy(rng, 0.030), reference, variance).corrected);
    }
    if (paired_difference(better, worse).sign == -1) ++found;
    if (paired_difference(better, same).sign != 0) ++false_positives;
  }
  // 0.042^2 / 0.030^2 = 1.96x the MRSE: found nearly always at k = 3; equal methods: about 5%
  // false winners.
  std::printf("found %d of %d, false winners %d\n", found, batches, false_positives);
  EXPECT_GT(found, 0.95 * batches);
  EXPECT_GE(false_positives, 0.025 * batches);
  EXPECT_LE(false_positives, 0.08 * batches);
  std::vector<double> a{1, 2}, b{1};
  EXPECT_THROW(paired_difference(a, b), std::invalid_argument);
  std::vector<double> one_a{1}, one_b{2};
  EXPECT_EQ(paired_difference(one_a, one_b).sign, 0);  // one pair: never significant
}

}  // namespace
}  // namespace penumbra
