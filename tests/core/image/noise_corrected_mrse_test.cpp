// The noise-corrected MRSE: a hand-computed example, the cases without a variance layer and with
// bad input, and its unbiasedness on synthetic images with known mean and variance (test and
// reference both gaussian around a known truth, the reference's variance layer a sample
// variance): the corrected MRSE averages to the test's true MRSE, the plain one does not, and
// the reference's deviation is the spread the reference's own noise gives it.

#include "core/image/noise_corrected_mrse.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

namespace penumbra {
namespace {

TEST(NoiseCorrectedMrse, HandComputedExample) {
  Image test(2, 1), reference(2, 1), variance(2, 1);
  test.rgb = {1.0f, 2.0f, 0.0f, 0.5f, 0.5f, 0.5f};
  reference.rgb = {1.5f, 2.0f, 0.0f, 1.0f, 0.25f, 0.5f};
  variance.rgb = {0.01f, 0.04f, 0.0f, 0.02f, 0.001f, 0.0f};
  const double eps = kMrseEpsilon;
  double plain = 0, term = 0;
  for (int i = 0; i < 6; ++i) {
    const double r = reference.rgb[i], d = double(test.rgb[i]) - r;
    plain += d * d / (r * r + eps);
    term += double(variance.rgb[i]) / (r * r + eps);
  }
  NoiseCorrectedError error = noise_corrected_mrse(test, reference, variance);
  EXPECT_TRUE(error.has_variance);
  EXPECT_DOUBLE_EQ(error.plain, plain / 6);
  EXPECT_DOUBLE_EQ(error.plain, mrse(test, reference));
  EXPECT_DOUBLE_EQ(error.reference_term, term / 6);
  EXPECT_DOUBLE_EQ(error.corrected, error.plain - error.reference_term);
  EXPECT_DOUBLE_EQ(error.reference_share(), error.reference_term / error.plain);
  // Deviation: per pixel the channels' sqrt(2) s^2 g add, then pixels in quadrature.
  double pixel[2] = {0, 0};
  for (int i = 0; i < 6; ++i) {
    const double r = reference.rgb[i];
    pixel[i / 3] += std::sqrt(2.0) * double(variance.rgb[i]) / (r * r + eps);
  }
  EXPECT_DOUBLE_EQ(error.reference_deviation,
                   std::sqrt(pixel[0] * pixel[0] + pixel[1] * pixel[1]) / 6);
  // A region: the second pixel alone.
  NoiseCorrectedError second = noise_corrected_mrse(test, reference, variance, Region{1, 0, 2, 1});
  EXPECT_DOUBLE_EQ(second.plain, mrse(test, reference, Region{1, 0, 2, 1}));
  EXPECT_DOUBLE_EQ(reference_noise_mrse(reference, variance, Region{0, 0, 2, 1}),
                   error.reference_term);
}

TEST(NoiseCorrectedMrse, WithoutAVarianceLayerItIsThePlainMrse) {
  Image test(3, 2), reference(3, 2);
  for (size_t i = 0; i < test.rgb.size(); ++i) {
    test.rgb[i] = 0.1f * float(i);
    reference.rgb[i] = 0.1f * float(i) + 0.05f;
  }
  NoiseCorrectedError error = noise_corrected_mrse(test, reference, Image());
  EXPECT_FALSE(error.has_variance);
  EXPECT_EQ(error.reference_term, 0.0);
  EXPECT_EQ(error.reference_deviation, 0.0);
  EXPECT_DOUBLE_EQ(error.corrected, mrse(test, reference));
  auto summary = noise_corrected_summary(test, reference, Image(), {{"left", {0, 0, 1, 2}}});
  ASSERT_EQ(summary.size(), 2u);
  EXPECT_DOUBLE_EQ(summary.at("left").plain, mrse(test, reference, Region{0, 0, 1, 2}));
}

TEST(NoiseCorrectedMrse, BadInputIsAnErrorNamingWhatIsWrong) {
  Image test(2, 2), reference(2, 2), variance(2, 2), small(1, 2);
  EXPECT_THROW(noise_corrected_mrse(test, small, Image()), std::invalid_argument);
  EXPECT_THROW(noise_corrected_mrse(test, reference, small), std::invalid_argument);
  variance.rgb[4] = -1.0f;
  try {
    noise_corrected_mrse(test, reference, variance);
    FAIL() << "a negative variance was accepted";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("pixel (1, 0)"), std::string::npos) << error.what();
  }
  variance.rgb[4] = NAN;
  EXPECT_THROW(noise_corrected_mrse(test, reference, variance), std::invalid_argument);
  variance.rgb[4] = 0;
  EXPECT_THROW(noise_corrected_mrse(test, reference, variance, Region{5, 5, 9, 9}),
               std::invalid_argument);
  try {
    noise_corrected_summary(test, reference, variance, {{"outside", {5, 5, 9, 9}}});
    FAIL() << "an empty region was accepted";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("'outside'"), std::string::npos) << error.what();
  }
  // Black pixels and a zero reference: finite.
  NoiseCorrectedError black = noise_corrected_mrse(test, reference, variance);
  EXPECT_EQ(black.plain, 0.0);
  EXPECT_EQ(black.reference_share(), 0.0);
}

// A synthetic truth mu per pixel channel; a test image mu + N(0, sigma_test^2); a reference
// mu + N(0, sigma_ref^2) whose variance layer is the sample variance of the mean of n samples,
// sigma_ref^2 chi^2_{n-1} / (n - 1).
struct Synthetic {
  int width = 48, height = 32;
  double test_relative = 0.03;       // sigma_test / mu
  double reference_relative = 0.03;  // sigma_ref / mu
  int reference_samples = 64;
  std::vector<double> mu;

  explicit Synthetic(uint32_t seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> value(0.05, 3.0);
    mu.resize(size_t(width) * height * 3);
    for (double& m : mu) m = value(rng);
  }
  double true_mrse() const {
    double sum = 0;
    for (double m : mu) {
      const double sigma = test_relative * m;
      sum += sigma * sigma / (m * m + kMrseEpsilon);
    }
    return sum / double(mu.size());
  }
  Image test(std::mt19937_64& rng) const {
    std::normal_distribution<double> normal;
    Image image(width, height);
    for (size_t i = 0; i < mu.size(); ++i)
      image.rgb[i] = float(mu[i] + test_relative * mu[i] * normal(rng));
    return image;
  }
  void reference(std::mt19937_64& rng, Image& color, Image& variance) const {
    std::normal_distribution<double> normal;
    std::chi_squared_distribution<double> chi2(reference_samples - 1);
    color = Image(width, height);
    variance = Image(width, height);
    for (size_t i = 0; i < mu.size(); ++i) {
      const double sigma = reference_relative * mu[i];
      color.rgb[i] = float(mu[i] + sigma * normal(rng));
      variance.rgb[i] = float(sigma * sigma * chi2(rng) / (reference_samples - 1));
    }
  }
};

TEST(NoiseCorrectedMrse, UnbiasedOnSyntheticImagesWithKnownMeanAndVariance) {
  Synthetic synthetic(7);
  const double truth = synthetic.true_mrse();
  std::mt19937_64 rng(11);
  const int trials = 300;
  std::vector<double> corrected, plain, shares;
  for (int t = 0; t < trials; ++t) {
    Image reference, variance;
    synthetic.reference(rng, reference, variance);
    NoiseCorrectedError error = noise_corrected_mrse(synthetic.test(rng), reference, variance);
    corrected.push_back(error.corrected);
    plain.push_back(error.plain);
    shares.push_back(error.reference_share());
  }
  auto mean_and_error = [](const std::vector<double>& values) {
    double mean = 0, squares = 0;
    for (double v : values) mean += v;
    mean /= double(values.size());
    for (double v : values) squares += (v - mean) * (v - mean);
    return std::pair{mean, std::sqrt(squares / double(values.size() - 1) / double(values.size()))};
  };
  auto [corrected_mean, corrected_error] = mean_and_error(corrected);
  auto [plain_mean, plain_error] = mean_and_error(plain);
  auto [share_mean, share_error] = mean_and_error(shares);
  // The residual bias is of order 3 (sigma_ref / mu)^2 = 0.27% of the truth; 4 standard errors
  // of the mean over the trials are about 1%.
  EXPECT_NEAR(corrected_mean, truth, 4 * corrected_error + 0.003 * truth)
      << "corrected " << corrected_mean << " +- " << corrected_error << ", truth " << truth;
  // Equal test and reference noise: the plain MRSE is about twice the truth, and half of it is
  // the reference's.
  EXPECT_GT(plain_mean - truth, 50 * plain_error);
  EXPECT_NEAR(plain_mean / truth, 2.0, 0.05);
  EXPECT_NEAR(share_mean, 0.5, 0.02) << share_error;
}

TEST(NoiseCorrectedMrse, ReferenceDeviationIsTheSpreadTheReferenceCauses) {
  // The test image is the truth, so the corrected MRSE varies only by the reference's own noise
  // (with a noisy test, the cross term -2 d e g varies too, but it is independent between
  // repeats and shows in their spread). Its standard deviation is what reference_deviation
  // predicts: the channels here are independent, so the prediction, which takes a pixel's
  // channels as correlated, is conservative by up to sqrt(3): checked against both bounds.
  Synthetic synthetic(3);
  synthetic.reference_samples = 4096;  // s^2 close to sigma^2, as the derivation assumes
  std::mt19937_64 rng(5);
  Image test(synthetic.width, synthetic.height);
  for (size_t i = 0; i < synthetic.mu.size(); ++i) test.rgb[i] = float(synthetic.mu[i]);
  std::vector<double> corrected;
  double predicted = 0;
  const int trials = 400;
  for (int t = 0; t < trials; ++t) {
    Image reference, variance;
    synthetic.reference(rng, reference, variance);
    NoiseCorrectedError error = noise_corrected_mrse(test, reference, variance);
    corrected.push_back(error.corrected);
    predicted += error.reference_deviation / trials;
  }
  double mean = 0, squares = 0;
  for (double v : corrected) mean += v;
  mean /= trials;
  for (double v : corrected) squares += (v - mean) * (v - mean);
  const double observed = std::sqrt(squares / (trials - 1));
  EXPECT_GT(predicted, 0.9 * observed) << "predicted " << predicted << ", observed " << observed;
  EXPECT_LT(predicted, 1.1 * std::sqrt(3.0) * observed)
      << "predicted " << predicted << ", observed " << observed;
}

}  // namespace
}  // namespace penumbra
