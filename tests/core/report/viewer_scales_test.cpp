// The comparison viewer's variance view and scales: the variance scale spans the decades of the
// relative variance's 1st and 99th percentiles, choose_viewer_scales gives the figure's and the
// difference's scales, and the page's section carries each image's variance layer (decoding to
// the layer within the encoding's bound), refusing a layer of the wrong size; without a reference
// each image is its own scale.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <random>

#include "core/image/metrics.h"
#include "core/report/batch_figure.h"
#include "core/report/batch_html.h"
#include "core/report/comparison_viewer.h"
#include "tests/support/viewer_images.h"

namespace penumbra {
namespace {

using testing::base64_decode;
using testing::wide_range_image;
using testing::worst_error;

// An image of `count` x 1 pixels of 0.5 and a variance layer whose relative variances
// var / (0.5^2 + 1e-6) run log-uniformly from 2e-5 to 3e-2.
std::pair<Image, Image> log_uniform_relative_variances(int count) {
  Image image(count, 1), variance(count, 1);
  for (int x = 0; x < count; ++x) {
    double relative = 2e-5 * std::pow(1.5e3, double(x) / (count - 1));
    image.set(x, 0, {0.5, 0.5, 0.5});
    double v = relative * (0.25 + kMrseEpsilon);
    variance.set(x, 0, {v, v, v});
  }
  return {image, variance};
}

TEST(ViewerScales, VarianceScaleSpansTheDecadesOfThePercentiles) {
  // Relative variances var / (ref^2 + 1e-6) from 2e-5 to 3e-2, log-uniform over 200 pixels: the
  // 1st percentile (index 2) is above 2e-5, the 99th (index 198) below 3e-2, so the scale is the
  // decades around them, [1e-5, 1e-1].
  const int count = 200;
  const auto [reference, variance] = log_uniform_relative_variances(count);
  const auto [low, high] = choose_variance_scale({&variance, nullptr}, reference);
  EXPECT_DOUBLE_EQ(low, 1e-5);
  EXPECT_DOUBLE_EQ(high, 1e-1);
  // No variance layer at all, or only zeros: the default scale.
  Image zero(count, 1);
  EXPECT_EQ(choose_variance_scale({nullptr}, reference), std::make_pair(1e-6, 1.0));
  EXPECT_EQ(choose_variance_scale({&zero}, reference), std::make_pair(1e-6, 1.0));
  Image small(4, 1);
  EXPECT_THROW(choose_variance_scale({&small}, reference), std::invalid_argument);
}

TEST(ViewerScales, SectionCarriesVarianceLayersAndTheSharedScales) {
  const int width = 24, height = 16;
  Image reference = wide_range_image(width, height, 5);
  Image method = wide_range_image(width, height, 6);
  Image variance = wide_range_image(width, height, 7);
  Image reference_variance = wide_range_image(width, height, 8);
  ComparisonViewerContent content;
  content.width = width;
  content.height = height;
  content.reference = {"reference", "bsdf+sa", "stratified",       256, 0, 0, &reference, {},
                       {},          0,         &reference_variance};
  content.methods.push_back({"sa", "sa", "stratified", 16, 0, 1.5, &method, {}, {}, 1, &variance});
  content.methods.push_back({"bsdf", "bsdf", "random", 16, 0, 1.5, &method, {}, {}, 1, nullptr});
  choose_viewer_scales(content);
  // The scales the report's figure and the coordinator's page use, from the same functions.
  EXPECT_EQ(content.exposure, choose_exposure(reference));
  EXPECT_EQ(content.error_scale, choose_error_scale({&method, &method}, reference));
  EXPECT_EQ(content.difference_scale, choose_difference_scale({&method, &method}, reference));
  const auto scale = choose_variance_scale({&variance}, reference);
  EXPECT_EQ(content.variance_low, scale.first);
  EXPECT_EQ(content.variance_high, scale.second);

  const std::string html = comparison_viewer_html(content);
  const std::string open = R"(<script type="application/json" id="viewer-data">)";
  const size_t payload = html.find(open) + open.size();
  ASSERT_NE(html.find(open), std::string::npos);
  nlohmann::json data =
      nlohmann::json::parse(html.substr(payload, html.find("</script>", payload) - payload));
  EXPECT_EQ(data["variance_scale"], nlohmann::json({scale.first, scale.second}));
  EXPECT_EQ(data["mrse_epsilon"], kMrseEpsilon);
  for (const auto& [json, image] : std::vector<std::pair<const nlohmann::json*, const Image*>>{
           {&data["reference"], &reference_variance}, {&data["methods"][0], &variance}}) {
    Image decoded =
        decode_viewer_image(base64_decode((*json)["variance"].get<std::string>()), width, height);
    EXPECT_LE(worst_error(*image, decoded), kViewerQuantization) << (*json)["label"];
  }
  EXPECT_FALSE(data["methods"][1].contains("variance"));

  Image small(8, 8);
  content.methods[0].variance = &small;
  try {
    comparison_viewer_html(content);
    FAIL() << "a wrong-size variance layer was accepted";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("sa: variance layer is 8x8, expected 24x16"),
              std::string::npos)
        << error.what();
  }
}

TEST(ViewerScales, WithoutAReferenceEachImageIsItsOwnScale) {
  // A farm job without a reference: the exposure of its image, the variance relative to the
  // image itself (the same decades as against a reference of those values), null in the data.
  const int count = 200;
  const auto [image, variance] = log_uniform_relative_variances(count);
  ComparisonViewerContent content;
  content.width = count;
  content.height = 1;
  content.methods.push_back({"sa", "sa", "stratified", 16, 0, 1.5, &image, {}, {}, 0, &variance});
  choose_viewer_scales(content);
  EXPECT_EQ(content.exposure, choose_exposure(image));
  EXPECT_EQ(content.error_scale, 1.0);
  EXPECT_EQ(content.difference_scale, 1.0);
  EXPECT_DOUBLE_EQ(content.variance_low, 1e-5);
  EXPECT_DOUBLE_EQ(content.variance_high, 1e-1);
  const std::string html = comparison_viewer_html(content);
  const std::string open = R"(<script type="application/json" id="viewer-data">)";
  ASSERT_NE(html.find(open), std::string::npos);
  const size_t payload = html.find(open) + open.size();
  nlohmann::json data =
      nlohmann::json::parse(html.substr(payload, html.find("</script>", payload) - payload));
  EXPECT_TRUE(data["reference"].is_null());
  ASSERT_EQ(data["methods"].size(), 1u);
  // Nothing at all to show is refused.
  content.methods.clear();
  EXPECT_THROW(choose_viewer_scales(content), std::invalid_argument);
  EXPECT_THROW(comparison_viewer_html(content), std::invalid_argument);
}

}  // namespace
}  // namespace penumbra
