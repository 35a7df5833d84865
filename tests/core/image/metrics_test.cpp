// Error metrics: MSE/RMSE against OpenImageIO's own ImageBufAlgo::compare, MRSE against a small
// hand-computed example and against its definition, regions (clipping, empty regions), the
// summary, and the least-squares log-log slope.

#include "core/image/metrics.h"

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

namespace penumbra {
namespace {

Image random_image(int width, int height, uint32_t seed, float scale = 1.0f) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> value(0.0f, scale);
  Image image(width, height);
  for (float& v : image.rgb) v = value(rng);
  return image;
}

// A read-only OIIO view of an Image's floats.
OIIO::ImageBuf as_image_buf(Image& image) {
  OIIO::ImageSpec spec(image.width, image.height, 3, OIIO::TypeDesc::FLOAT);
  return OIIO::ImageBuf(spec, image.rgb.data());
}

TEST(Mse, AgreesWithOpenImageIoCompare) {
  for (uint32_t seed = 1; seed <= 5; ++seed) {
    Image test = random_image(61 + seed, 29 + 2 * seed, seed, 4.0f);
    Image reference = random_image(61 + seed, 29 + 2 * seed, 100 + seed, 4.0f);
    OIIO::ImageBuf a = as_image_buf(test), b = as_image_buf(reference);
    OIIO::ImageBufAlgo::CompareResults result = OIIO::ImageBufAlgo::compare(a, b, 1e9f, 1e9f);
    ASSERT_FALSE(result.error);
    // OIIO: rms_error = sqrt(mean over pixels and channels of the squared difference). Its sums
    // run in another order (and partly in float), so agreement is to float precision, 1e-6.
    double expected_mse = result.rms_error * result.rms_error;
    EXPECT_NEAR(mse(test, reference), expected_mse, 1e-6 * expected_mse) << seed;
    EXPECT_NEAR(rmse(test, reference), result.rms_error, 1e-6 * result.rms_error) << seed;
  }
}

TEST(Mse, RegionAgreesWithOpenImageIoCompareOnThatRoi) {
  Image test = random_image(40, 30, 7, 2.0f);
  Image reference = random_image(40, 30, 8, 2.0f);
  OIIO::ImageBuf a = as_image_buf(test), b = as_image_buf(reference);
  Region region{5, 3, 17, 26};
  OIIO::ROI roi(region.x0, region.x1, region.y0, region.y1, 0, 1, 0, 3);
  auto result = OIIO::ImageBufAlgo::compare(a, b, 1e9f, 1e9f, roi);
  ASSERT_FALSE(result.error);
  double expected = result.rms_error * result.rms_error;
  EXPECT_NEAR(mse(test, reference, region), expected, 1e-6 * expected);
}

TEST(Mrse, HandComputedExample) {
  // 2x1 image. Values are exact binary fractions so the expected sum is exact up to division.
  Image reference(2, 1), test(2, 1);
  reference.set(0, 0, {1.0, 2.0, 0.0});
  reference.set(1, 0, {0.5, 0.0, 4.0});
  test.set(0, 0, {1.5, 2.0, 0.0009765625});  // 2^-10
  test.set(1, 0, {0.5, 1.0, 2.0});
  const double eps = 1e-6;
  // Per channel (p - r)^2 / (r^2 + eps):
  //   (0.5)^2 / (1 + eps), 0, 2^-20 / eps, 0, 1 / eps, (-2)^2 / (16 + eps)
  double expected =
      (0.25 / (1 + eps) + 0.0 + 0x1p-20 / eps + 0.0 + 1.0 / eps + 4.0 / (16 + eps)) / 6.0;
  EXPECT_NEAR(mrse(test, reference), expected, 1e-14 * expected);
  // MSE of the same: (0.25 + 2^-20 + 1 + 4) / 6.
  EXPECT_NEAR(mse(test, reference), (0.25 + 0x1p-20 + 1.0 + 4.0) / 6.0, 1e-15);
  // A different epsilon changes the zero-reference terms only.
  double expected_eps1 = (0.25 / 2 + 0x1p-20 / 1 + 1.0 / 1 + 4.0 / 17) / 6.0;
  EXPECT_NEAR(mrse(test, reference, 1.0), expected_eps1, 1e-15);
}

TEST(Mrse, MatchesItsDefinitionOnRandomImages) {
  Image test = random_image(33, 21, 11, 3.0f);
  Image reference = random_image(33, 21, 12, 3.0f);
  double sum = 0;
  for (size_t i = 0; i < test.rgb.size(); ++i) {
    double p = test.rgb[i], r = reference.rgb[i];
    sum += (p - r) * (p - r) / (r * r + kMrseEpsilon);
  }
  double expected = sum / double(test.rgb.size());
  EXPECT_NEAR(mrse(test, reference), expected, 1e-12 * expected);
  EXPECT_EQ(mrse(reference, reference), 0.0);
  EXPECT_EQ(mse(reference, reference), 0.0);
}

// Copies a rectangle of an image.
Image crop(const Image& image, const Region& r) {
  Image out(r.x1 - r.x0, r.y1 - r.y0);
  for (int y = r.y0; y < r.y1; ++y)
    for (int x = r.x0; x < r.x1; ++x) out.set(x - r.x0, y - r.y0, image.at(x, y));
  return out;
}

TEST(Regions, RegionEqualsTheMetricOfTheCrop) {
  Image test = random_image(30, 20, 21);
  Image reference = random_image(30, 20, 22);
  Region region{4, 7, 19, 15};
  Image test_crop = crop(test, region), reference_crop = crop(reference, region);
  EXPECT_NEAR(mrse(test, reference, region), mrse(test_crop, reference_crop), 1e-12);
  EXPECT_NEAR(mse(test, reference, region), mse(test_crop, reference_crop), 1e-15);
  // The whole image as a region is the whole-image metric.
  EXPECT_EQ(mrse(test, reference, Region{0, 0, 30, 20}), mrse(test, reference));
}

TEST(Regions, AreClippedToTheImage) {
  Image test = random_image(30, 20, 23);
  Image reference = random_image(30, 20, 24);
  Region outside{-10, 12, 8, 40};
  Region clipped{0, 12, 8, 20};
  EXPECT_EQ(mrse(test, reference, outside), mrse(test, reference, clipped));
  EXPECT_EQ(mse(test, reference, outside), mse(test, reference, clipped));
}

TEST(Regions, EmptyRegionsAndSizeMismatchThrow) {
  Image test = random_image(10, 10, 25);
  Image reference = random_image(10, 10, 26);
  EXPECT_THROW(mrse(test, reference, Region{3, 3, 3, 8}), std::invalid_argument);
  EXPECT_THROW(mrse(test, reference, Region{5, 5, 2, 8}), std::invalid_argument);
  EXPECT_THROW(mse(test, reference, Region{10, 0, 20, 10}), std::invalid_argument);
  EXPECT_THROW(mse(test, reference, Region{-5, -5, 0, 0}), std::invalid_argument);
  EXPECT_THROW(mrse(test, random_image(10, 11, 27)), std::invalid_argument);
  EXPECT_THROW(mse(test, random_image(11, 10, 28)), std::invalid_argument);
  EXPECT_THROW(mrse(Image(), Image()), std::invalid_argument);
}

TEST(ErrorSummary, HasTheImageAndEveryRegion) {
  Image test = random_image(16, 12, 31);
  Image reference = random_image(16, 12, 32);
  std::map<std::string, Region> regions{{"penumbra", {2, 2, 8, 8}}, {"floor", {0, 8, 16, 12}}};
  auto summary = error_summary(test, reference, regions);
  ASSERT_EQ(summary.size(), 3u);
  EXPECT_EQ(summary.at("image").mrse, mrse(test, reference));
  EXPECT_EQ(summary.at("image").mse, mse(test, reference));
  EXPECT_DOUBLE_EQ(summary.at("image").rmse, rmse(test, reference));
  for (const auto& [name, region] : regions) {
    EXPECT_EQ(summary.at(name).mrse, mrse(test, reference, region)) << name;
    EXPECT_EQ(summary.at(name).mse, mse(test, reference, region)) << name;
    EXPECT_DOUBLE_EQ(summary.at(name).rmse, std::sqrt(mse(test, reference, region))) << name;
  }
  regions["nowhere"] = {20, 20, 30, 30};
  try {
    error_summary(test, reference, regions);
    FAIL() << "empty region accepted";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("nowhere"), std::string::npos) << error.what();
  }
}

TEST(LogLogSlope, InversePowerLawHasItsExponent) {
  std::vector<double> x, y;
  for (int k = 1; k <= 10; ++k) {
    x.push_back(std::ldexp(1.0, k));
    y.push_back(3.7 * std::pow(x.back(), -2.0));
  }
  EXPECT_NEAR(log_log_slope(x, y), -2.0, 1e-12);
  // Other exponents and non-power-of-two abscissae.
  std::vector<double> x2{3, 7, 19, 50, 333}, y2;
  for (double v : x2) y2.push_back(0.01 * std::pow(v, -0.5));
  EXPECT_NEAR(log_log_slope(x2, y2), -0.5, 1e-12);
}

TEST(LogLogSlope, IsTheLeastSquaresSlopeOfNoisyData) {
  // log y = 1 - 1.5 log x + e with e alternating +-0.1: the fit of an alternating residual
  // over symmetric points is not exactly -1.5; compare with the normal equations computed here.
  std::vector<double> x{1, 2, 4, 8, 16}, y;
  double e[] = {0.1, -0.1, 0.1, -0.1, 0.1};
  for (size_t i = 0; i < x.size(); ++i) y.push_back(std::exp(1 - 1.5 * std::log(x[i]) + e[i]));
  double mx = 0, my = 0;
  for (size_t i = 0; i < x.size(); ++i) {
    mx += std::log(x[i]) / 5;
    my += std::log(y[i]) / 5;
  }
  double sxy = 0, sxx = 0;
  for (size_t i = 0; i < x.size(); ++i) {
    sxy += (std::log(x[i]) - mx) * (std::log(y[i]) - my);
    sxx += (std::log(x[i]) - mx) * (std::log(x[i]) - mx);
  }
  EXPECT_NEAR(log_log_slope(x, y), sxy / sxx, 1e-12);
}

TEST(LogLogSlope, SkipsNonPositivePairsAndRefusesTooFew) {
  std::vector<double> x{0, 1, 2, -3, 4}, y{5, 1, 0.25, 1, 0.0625};
  EXPECT_NEAR(log_log_slope(x, y), -2.0, 1e-12);
  std::vector<double> one_x{1, 0}, one_y{1, 1};
  EXPECT_THROW(log_log_slope(one_x, one_y), std::invalid_argument);
  std::vector<double> same_x{2, 2, 2}, same_y{1, 2, 3};
  EXPECT_THROW(log_log_slope(same_x, same_y), std::invalid_argument);
  std::vector<double> short_y{1, 2};
  EXPECT_THROW(log_log_slope(same_x, short_y), std::invalid_argument);
}

}  // namespace
}  // namespace penumbra
