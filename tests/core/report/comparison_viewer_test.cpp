// The comparison viewer's writer: the RGBE encoding decodes to every channel within
// kViewerQuantization of its pixel's brightest channel (and the bound is tight), black, negative
// and non-finite values are stored as 0, and the page's section holds every image's data, which
// decodes to the films' values, with the numbers and regions beside them.
#include "core/report/comparison_viewer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <random>

#include "core/report/batch_html.h"
#include "tests/support/viewer_images.h"

namespace penumbra {
namespace {

using testing::base64_decode;
using testing::wide_range_image;
using testing::worst_error;

TEST(ComparisonViewer, EncodingDecodesWithinQuantization) {
  Image image = wide_range_image(97, 61, 1);
  Image decoded = decode_viewer_image(encode_viewer_image(image), image.width, image.height);
  ASSERT_EQ(decoded.width, image.width);
  ASSERT_EQ(decoded.height, image.height);
  double worst = worst_error(image, decoded);
  EXPECT_LE(worst, kViewerQuantization);
  // The bound is nearly reached (rounding: the error is up to half a step, 1/256 of the brightest
  // channel just above a power of two).
  EXPECT_GT(worst, kViewerQuantization / 1.1);

  // A brightest channel that would round to mantissa 256 moves to the next exponent.
  Image edge(1, 1);
  edge.set(0, 0, {0.9995, 0.3, 0.0});
  Image back = decode_viewer_image(encode_viewer_image(edge), 1, 1);
  EXPECT_EQ(back.at(0, 0).x, 1.0);
  EXPECT_NEAR(back.at(0, 0).y, 0.3, 0.9995 * kViewerQuantization);
}

TEST(ComparisonViewer, InvalidValuesAreBlack) {
  Image image(4, 1);
  image.set(0, 0, {-1, 2, 0});
  image.set(1, 0, {NAN, INFINITY, 1});
  image.set(2, 0, {1e-40, 0, 0});  // below 2^-120
  image.set(3, 0, {0.5, 0.25, 0.125});
  Image decoded = decode_viewer_image(encode_viewer_image(image), 4, 1);
  EXPECT_EQ(decoded.at(0, 0).x, 0.0);
  EXPECT_EQ(decoded.at(0, 0).y, 2.0);  // powers of two and zero are exact
  EXPECT_EQ(decoded.at(0, 0).z, 0.0);
  EXPECT_EQ(decoded.at(1, 0).x, 0.0);
  EXPECT_EQ(decoded.at(1, 0).y, 0.0);
  EXPECT_NEAR(decoded.at(1, 0).z, 1.0, kViewerQuantization);
  EXPECT_EQ(decoded.at(2, 0).x, 0.0);
  for (size_t c = 0; c < 3; ++c) EXPECT_TRUE(std::isfinite(decoded.rgb[3 * 3 + c]));
  EXPECT_EQ(decoded.at(3, 0).x, 0.5);
  EXPECT_EQ(decoded.at(3, 0).z, 0.125);
  for (const float value : decoded.rgb) EXPECT_TRUE(std::isfinite(value));
}

TEST(ComparisonViewer, SmoothImagesCompressWell) {
  // A smooth gradient: the planes are repetitive, so zlib brings 4 bytes per pixel well down.
  Image image(256, 128);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) image.set(x, y, {x / 256.0, y / 128.0, 0.5});
  const std::string bytes = encode_viewer_image(image);
  EXPECT_LT(bytes.size(), size_t(image.width) * image.height / 4);
  EXPECT_THROW(decode_viewer_image(bytes, 255, 128), std::runtime_error);
  EXPECT_THROW(decode_viewer_image("not zlib", 4, 4), std::runtime_error);
}

TEST(ComparisonViewer, SectionHoldsEveryImageAndItsNumbers) {
  const int width = 40, height = 30;
  Image reference = wide_range_image(width, height, 2);
  Image first = wide_range_image(width, height, 3);
  Image second = wide_range_image(width, height, 4);
  ComparisonViewerContent content;
  content.width = width;
  content.height = height;
  content.exposure = 0.75;
  content.error_scale = 2;
  content.difference_scale = choose_difference_scale({&first, &second}, reference);
  content.reference = {"reference", "bsdf+sa", "stratified", 256, 0, 0, &reference, {}, {}, 0};
  MeanInterval interval;
  interval.count = 3;
  interval.mean = 0.25;
  interval.half_width = 0.05;
  interval.has_interval = true;
  content.methods.push_back(
      {"sa", "sa", "stratified", 16, 0, 1.5, &first, {{"image", 0.3}}, {{"image", interval}}, 3});
  content.methods.push_back(
      {"odd </script> label", "bsdf", "random", 8, 1, 1.25, &second, {{"image", 0.5}}, {}, 1});
  content.regions.push_back({"penumbra", {4, 5, 20, 25}});
  const std::string html = comparison_viewer_html(content);

  // The script and style are in the section; no "</script>" but the three closing tags.
  EXPECT_NE(html.find(std::string(comparison_viewer_script()).substr(0, 200)), std::string::npos);
  EXPECT_NE(html.find(std::string(comparison_viewer_style()).substr(0, 100)), std::string::npos);
  size_t closings = 0;
  for (size_t at = html.find("</script>"); at != std::string::npos;
       at = html.find("</script>", at + 1))
    ++closings;
  EXPECT_EQ(closings, 2u);  // the data and the viewer's script

  // Found by string search: libstdc++'s std::regex recurses once per character it matches, so a
  // payload of many kilobytes overflows the stack (under AddressSanitizer's larger frames first).
  const std::string open = R"(<script type="application/json" id="viewer-data">)";
  const size_t begin = html.find(open);
  ASSERT_NE(begin, std::string::npos);
  const size_t payload = begin + open.size();
  const size_t end = html.find("</script>", payload);
  ASSERT_NE(end, std::string::npos);
  EXPECT_EQ(html.find('<', payload), end);  // the payload holds no '<'
  nlohmann::json data = nlohmann::json::parse(html.substr(payload, end - payload));
  EXPECT_EQ(data["encoding"], kViewerImageEncoding);
  EXPECT_EQ(data["width"], width);
  EXPECT_EQ(data["height"], height);
  EXPECT_EQ(data["exposure"], 0.75);
  EXPECT_EQ(data["error_scale"], 2.0);
  EXPECT_EQ(data["regions"][0]["name"], "penumbra");
  EXPECT_EQ(data["regions"][0]["rect"], nlohmann::json({4, 5, 20, 25}));
  EXPECT_EQ(data["methods"][1]["label"], "odd </script> label");
  EXPECT_EQ(data["methods"][0]["mrse"]["image"], 0.3);
  EXPECT_EQ(data["methods"][0]["corrected"]["image"]["lower"], 0.2);
  EXPECT_EQ(data["methods"][0]["corrected"]["image"]["upper"], 0.3);
  EXPECT_EQ(data["methods"][0]["repeats"], 3);
  EXPECT_FALSE(data["methods"][1]["corrected"].contains("image"));

  const std::vector<std::pair<const nlohmann::json*, const Image*>> expected = {
      {&data["reference"], &reference},
      {&data["methods"][0], &first},
      {&data["methods"][1], &second}};
  for (const auto& [json, image] : expected) {
    Image decoded =
        decode_viewer_image(base64_decode((*json)["data"].get<std::string>()), width, height);
    EXPECT_LE(worst_error(*image, decoded), kViewerQuantization) << (*json)["label"];
  }

  ComparisonViewerContent wrong = content;
  Image small(8, 8);
  wrong.methods[0].image = &small;
  try {
    comparison_viewer_html(wrong);
    FAIL() << "a wrong-size image was accepted";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("sa: image is 8x8, expected 40x30"), std::string::npos)
        << error.what();
  }
}

TEST(ComparisonViewer, DifferenceScaleIsThe99thPercentile) {
  Image reference(100, 1), image(100, 1);
  for (int x = 0; x < 100; ++x) image.set(x, 0, {double(x + 1), double(x + 1), double(x + 1)});
  // |mean(x - ref)| is 1..100; the 99th percentile (index 99 of 100) is 100.
  EXPECT_EQ(choose_difference_scale({&image}, reference), 100.0);
  EXPECT_EQ(choose_difference_scale({&reference}, reference), 1.0);
}

}  // namespace
}  // namespace penumbra
