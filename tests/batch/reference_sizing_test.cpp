// Sizing an auto reference (core/batch/reference_sizing.h) on synthetic variance images whose
// noise per sample has a closed form, through noise_per_sample (core/image/noise_corrected_mrse.h)
// as the batch manager measures it from its probes.
#include "core/batch/reference_sizing.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "core/image/noise_corrected_mrse.h"

namespace penumbra {
namespace {

constexpr int kWidth = 40, kHeight = 30;
constexpr double kDenominator = 0.5;  // the estimate of the true image, the same everywhere
constexpr double kWeight = 1.0 / (kDenominator * kDenominator + kMrseEpsilon);

Image constant_image(double value) {
  Image image(kWidth, kHeight);
  for (float& v : image.rgb) v = float(value);
  return image;
}

// A variance of the mean at `spp` whose per-sample variance is c * (x + 1) in every channel.
Image variance_growing_in_x(double c, uint32_t spp) {
  Image image(kWidth, kHeight);
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x) {
      const float v = float(c * (x + 1) / spp);
      image.set(x, y, {v, v, v});
    }
  return image;
}

// ... and c * (y + 1).
Image variance_growing_in_y(double c, uint32_t spp) {
  Image image(kWidth, kHeight);
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x) {
      const float v = float(c * (y + 1) / spp);
      image.set(x, y, {v, v, v});
    }
  return image;
}

// Mean of (k + 1) over k in [k0, k1): (k0 + k1 + 1) / 2.
double mean_of_index_plus_one(int k0, int k1) {
  return (k0 + k1 + 1) / 2.0;
}

TEST(ReferenceSizing, NoisePerSampleIsTheClosedForm) {
  const Image denominator = constant_image(kDenominator);
  const Region image{0, 0, kWidth, kHeight};
  const Region corner{10, 5, 20, 25};
  // The probe's spp cancels: per-sample variance c (x + 1) whatever it was measured at.
  for (uint32_t spp : {2u, 8u, 64u}) {
    const Image variance = variance_growing_in_x(3e-3, spp);
    EXPECT_NEAR(noise_per_sample(variance, spp, denominator, image),
                3e-3 * mean_of_index_plus_one(0, kWidth) * kWeight, 1e-6 * 3e-3 * 20 * kWeight);
    EXPECT_NEAR(noise_per_sample(variance, spp, denominator, corner),
                3e-3 * mean_of_index_plus_one(10, 20) * kWeight, 1e-6 * 3e-3 * 15 * kWeight);
  }
  EXPECT_THROW(noise_per_sample(Image(), 8, denominator, image), std::invalid_argument);
}

TEST(ReferenceSizing, SppIsTheClosedFormRoundedUpToAQuarterOctave) {
  const Image denominator = constant_image(kDenominator);
  const uint32_t probe = 8;
  // The reference method: per-sample variance 0.02 (x + 1); two methods: 0.05 (x + 1) at 64 spp
  // and 0.01 (y + 1) at 100 spp, the second one the better in the image (0.155 < 0.78 per pixel
  // on average, over their spp).
  const Image reference = variance_growing_in_x(0.02, probe);
  const Image a = variance_growing_in_x(0.05, probe);
  const Image b = variance_growing_in_y(0.01, probe);
  const std::vector<std::pair<std::string, Region>> regions = {
      {"image", Region{0, 0, kWidth, kHeight}}, {"right", Region{30, 0, 40, 10}}};
  ReferenceSizingRequest request;
  request.target_share = 0.01;
  request.seconds_per_pass = 0.002;
  request.max_seconds = 1e6;
  for (const auto& [name, rect] : regions) {
    ReferenceSizingRegion region{name, noise_per_sample(reference, probe, denominator, rect), {}};
    region.expected.push_back(noise_per_sample(a, probe, denominator, rect) / 64);
    region.expected.push_back(noise_per_sample(b, probe, denominator, rect) / 100);
    request.regions.push_back(region);
  }
  // Closed forms per region: a_ref = 0.02 mx w, best = min(0.05 mx w / 64, 0.01 my w / 100).
  auto required = [&](int x0, int x1, int y0, int y1) {
    const double mx = mean_of_index_plus_one(x0, x1), my = mean_of_index_plus_one(y0, y1);
    const double best = std::min(0.05 * mx / 64, 0.01 * my / 100) * kWeight;
    return 0.02 * mx * kWeight / (0.01 * best);
  };
  const double in_image = required(0, 40, 0, 30), in_right = required(30, 40, 0, 10);
  ASSERT_GT(in_right, in_image);  // the bright-noise corner with the low-noise rows decides
  const ReferenceSizing sizing = size_reference(request);
  EXPECT_NEAR(sizing.required_spp, in_right, 1e-5 * in_right);
  EXPECT_EQ(sizing.deciding_region, "right");
  EXPECT_EQ(sizing.best_method, 1);
  EXPECT_FALSE(sizing.capped);
  EXPECT_EQ(sizing.spp, uint32_t(quarter_octave_ceil(in_right)));
  EXPECT_GE(double(sizing.spp), in_right);
  EXPECT_LT(double(sizing.spp), in_right * std::exp2(0.25) + 1);
  // At the chosen spp the reference's term is at most 1% of the best error, and the predicted
  // share is r / (1 + r).
  const double ratio = in_right / sizing.spp * 0.01;
  EXPECT_NEAR(sizing.predicted_ratio, ratio, 1e-5 * ratio);
  EXPECT_LE(sizing.predicted_ratio, 0.01 * (1 + 1e-9));
  EXPECT_NEAR(sizing.predicted_share, ratio / (1 + ratio), 1e-5 * ratio);
  EXPECT_NEAR(sizing.predicted_seconds, sizing.spp * 0.002, 1e-9 * sizing.spp);

  // A compute cap below the need binds: floor(max_seconds / seconds_per_pass) passes, and the
  // prediction says how far from the target that leaves the reference.
  request.max_seconds = 1.0;  // 500 passes
  ASSERT_GT(in_right, 500);
  const ReferenceSizing capped = size_reference(request);
  EXPECT_TRUE(capped.capped);
  EXPECT_EQ(capped.spp, 500u);
  EXPECT_NEAR(capped.predicted_ratio, in_right / 500 * 0.01, 1e-5 * in_right / 500 * 0.01);
  EXPECT_GT(capped.predicted_share, 0.01);

  // Ten times the target share: a tenth of the spp.
  request.max_seconds = 1e6;
  request.target_share = 0.1;
  EXPECT_NEAR(size_reference(request).required_spp, in_right / 10, 1e-5 * in_right);
}

TEST(ReferenceSizing, EdgeCases) {
  // A noise-free reference needs one pass; a region without error is skipped.
  ReferenceSizingRequest request;
  request.regions = {{"image", 0.0, {0.5, 0.2}}, {"black", 1.0, {0.0, 0.0}}};
  ReferenceSizing sizing = size_reference(request);
  EXPECT_EQ(sizing.spp, 1u);
  EXPECT_FALSE(sizing.capped);
  EXPECT_EQ(sizing.deciding_region, "image");
  // The spp limit caps too.
  request.regions = {{"image", 1.0, {1e-9}}};
  request.max_spp = 4096;
  sizing = size_reference(request);
  EXPECT_TRUE(sizing.capped);
  EXPECT_EQ(sizing.spp, 4096u);
  // Bad input.
  request.target_share = 0;
  EXPECT_THROW(size_reference(request), std::invalid_argument);
  request.target_share = 0.01;
  request.regions = {{"image", -1.0, {0.1}}};
  EXPECT_THROW(size_reference(request), std::invalid_argument);
  request.regions = {{"image", 1.0, {}}};
  EXPECT_THROW(size_reference(request), std::invalid_argument);
  request.regions = {{"image", 1.0, {std::nan("")}}};
  EXPECT_THROW(size_reference(request), std::invalid_argument);
}

TEST(ReferenceSizing, QuarterOctaveGrid) {
  EXPECT_EQ(quarter_octave_ceil(0.3), 1);
  EXPECT_EQ(quarter_octave_ceil(1), 1);
  EXPECT_EQ(quarter_octave_ceil(1.01), 2);
  EXPECT_EQ(quarter_octave_ceil(1000), 1024);  // 2^10
  EXPECT_EQ(quarter_octave_ceil(1024), 1024);
  EXPECT_EQ(quarter_octave_ceil(1025), 1218);  // ceil(2^10.25) = ceil(1217.75)
  EXPECT_EQ(quarter_octave_ceil(1218), 1218);
  EXPECT_EQ(quarter_octave_ceil(1219), 1449);  // ceil(2^10.5) = ceil(1448.15)
  // Always at or above x, and within a quarter octave (plus the integer rounding).
  for (double x = 1; x < 1e6; x *= 1.37) {
    const double grid = quarter_octave_ceil(x);
    EXPECT_GE(grid, x);
    EXPECT_LE(grid, std::ceil(x * std::exp2(0.25)) + 1) << x;
  }
}

}  // namespace
}  // namespace penumbra
