// Charts: PNG and SVG files are produced with the asked size, the PNG has drawn (non-background)
// and coloured pixels, bad input is refused before PLplot sees it, charts drawn from two threads
// at once both come out, and the least-squares fit of a power law has its exponent as slope.

#include "core/image/chart.h"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "image_test_support.h"

namespace penumbra {
namespace {

namespace fs = std::filesystem;

using image_test::test_directory;

ChartSpec convergence_chart() {
  ChartSpec spec;
  spec.title = "MRSE against samples #1";
  spec.x_label = "samples per pixel";
  spec.y_label = "MRSE";
  spec.log_x = spec.log_y = true;
  spec.width = 640;
  spec.height = 480;
  ChartSeries points{"points", {}, {}, {}, std::nullopt};
  ChartSeries lines{"lines", {}, {}, {}, std::nullopt};
  for (int k = 0; k <= 8; ++k) {
    double n = std::ldexp(1.0, k);
    points.x.push_back(n);
    points.y.push_back(0.5 / n);
    points.y_error.push_back(0.1 / n);
    lines.x.push_back(n);
    lines.y.push_back(0.2 * std::pow(n, -1.5));
  }
  points.fit = fit_line(points, true, true);
  lines.fit = fit_line(lines, true, true);
  lines.markers = false;
  spec.series = {points, lines};
  return spec;
}

TEST(FitLine, PowerLawSlopeAndIntercept) {
  ChartSeries series{"power", {1, 2, 4, 8, 16}, {}, {}, std::nullopt};
  for (double x : series.x) series.y.push_back(3.0 * std::pow(x, -2.0));
  LineFit fit = fit_line(series, true, true);
  EXPECT_NEAR(fit.slope, -2.0, 1e-12);
  EXPECT_NEAR(fit.intercept, std::log10(3.0), 1e-12);
  LineFit linear =
      fit_line(ChartSeries{"line", {0, 1, 2}, {1, 3, 5}, {}, std::nullopt}, false, false);
  EXPECT_NEAR(linear.slope, 2.0, 1e-12);
  EXPECT_NEAR(linear.intercept, 1.0, 1e-12);
  EXPECT_THROW(fit_line(ChartSeries{"one", {1, -1}, {1, 1}, {}, std::nullopt}, true, true),
               std::invalid_argument);
}

TEST(LineChart, PngHasTheSizeAndDrawnPixels) {
  std::string path = (test_directory() / "convergence.png").string();
  write_line_chart(path, convergence_chart());
  ASSERT_GT(fs::file_size(path), 0u);

  auto input = OIIO::ImageInput::open(path);
  ASSERT_TRUE(input) << OIIO::geterror();
  const OIIO::ImageSpec& spec = input->spec();
  EXPECT_EQ(spec.width, 640);
  EXPECT_EQ(spec.height, 480);
  ASSERT_GE(spec.nchannels, 3);
  std::vector<uint8_t> pixels(size_t(spec.width) * spec.height * spec.nchannels);
  ASSERT_TRUE(input->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::UINT8, pixels.data()));
  size_t drawn = 0, coloured = 0, white = 0;
  for (size_t p = 0; p < size_t(spec.width) * spec.height; ++p) {
    const uint8_t* c = &pixels[p * spec.nchannels];
    if (c[0] == 255 && c[1] == 255 && c[2] == 255)
      ++white;
    else
      ++drawn;
    if (std::abs(int(c[0]) - int(c[2])) > 60 || std::abs(int(c[1]) - int(c[2])) > 60) ++coloured;
  }
  size_t total = size_t(spec.width) * spec.height;
  // A white page with axes, grid, text, two coloured series and a legend.
  EXPECT_GT(white, total / 2);
  EXPECT_GT(drawn, total / 100);
  EXPECT_GT(coloured, 200u);
}

TEST(LineChart, SvgIsWritten) {
  std::string path = (test_directory() / "convergence.svg").string();
  write_line_chart(path, convergence_chart());
  std::ifstream file(path);
  std::stringstream text;
  text << file.rdbuf();
  EXPECT_NE(text.str().find("<svg"), std::string::npos);
  EXPECT_NE(text.str().find("</svg>"), std::string::npos);
  EXPECT_GT(text.str().size(), 1000u);
}

// A log axis always holds two decades, so that it has two labels: data within one decade
// (a time chart of 0.3 to 0.8 s) is drawn over the decades around it; wider data is left alone.
TEST(LineChart, LogAxesHoldAtLeastTwoDecades) {
  auto decades = [](std::pair<double, double> range) {
    return std::floor(range.second) - std::ceil(range.first) + 1;
  };
  EXPECT_EQ(log_axis_range(std::log10(0.3), std::log10(0.8)), std::make_pair(-1.0, 0.0));
  EXPECT_EQ(log_axis_range(-3.2, -3.1), std::make_pair(-4.0, -3.0));
  EXPECT_EQ(log_axis_range(0.2, 1.7), std::make_pair(0.0, 2.0));
  EXPECT_EQ(log_axis_range(-3.2, -1.1), std::make_pair(-3.2, -1.1));
  EXPECT_EQ(log_axis_range(2.0, 2.0), std::make_pair(2.0, 3.0));
  for (double low = -5; low < 5; low += 0.37)
    for (double span = 0; span < 3; span += 0.29)
      EXPECT_GE(decades(log_axis_range(low, low + span)), 2) << low << " " << span;
}

TEST(LineChart, LinearAxesAndSinglePointSeries) {
  ChartSpec spec;
  spec.title = "one point";
  spec.series = {ChartSeries{"p", {1}, {2}, {}, std::nullopt}};
  std::string path = (test_directory() / "single.png").string();
  write_line_chart(path, spec);
  EXPECT_GT(fs::file_size(path), 0u);
}

TEST(LineChart, BadInputIsRefused) {
  ChartSpec spec = convergence_chart();
  EXPECT_THROW(write_line_chart((test_directory() / "chart.gif").string(), spec),
               std::invalid_argument);
  ChartSpec empty;
  EXPECT_THROW(write_line_chart((test_directory() / "empty.png").string(), empty),
               std::invalid_argument);
  ChartSpec unplottable;
  unplottable.log_y = true;
  unplottable.series = {ChartSeries{"zeros", {1, 2}, {0, -1}, {}, std::nullopt}};
  EXPECT_THROW(write_line_chart((test_directory() / "zeros.png").string(), unplottable),
               std::invalid_argument);
  ChartSpec mismatched;
  mismatched.series = {ChartSeries{"bad", {1, 2}, {1}, {}, std::nullopt}};
  EXPECT_THROW(write_line_chart((test_directory() / "bad.png").string(), mismatched),
               std::invalid_argument);
  std::string unwritable = (test_directory() / "missing-dir" / "chart.png").string();
  try {
    write_line_chart(unwritable, spec);
    FAIL() << "wrote into a missing directory";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find(unwritable), std::string::npos);
  }
}

TEST(LineChart, TwoThreadsAtOnce) {
  std::string a = (test_directory() / "thread-a.png").string();
  std::string b = (test_directory() / "thread-b.svg").string();
  std::thread first([&] {
    for (int i = 0; i < 3; ++i) write_line_chart(a, convergence_chart());
  });
  std::thread second([&] {
    for (int i = 0; i < 3; ++i) write_line_chart(b, convergence_chart());
  });
  first.join();
  second.join();
  auto input = OIIO::ImageInput::open(a);
  ASSERT_TRUE(input);
  EXPECT_EQ(input->spec().width, 640);
  EXPECT_GT(fs::file_size(b), 1000u);
}

}  // namespace
}  // namespace penumbra
