// Line charts with PLplot (libplplot-dev, cairo drivers svgcairo and pngcairo).
//
// PLplot keeps global state (the stream table, the current stream), so every chart is drawn under
// one mutex. PLplot's error handler ends the process, so everything it could complain about (the
// device, the output file, the ranges) is checked here before PLplot sees it.

#include "core/image/chart.h"

#include <plplot/plstream.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

// LeakSanitizer (the sanitizer test run keeps leak detection on): PLplot keeps the drivers it
// loaded through libltdl, and cairo's fontconfig its configuration, for the life of the process.
// They are caches of those libraries, reported as leaks at exit; suppress exactly those two.
#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define PENUMBRA_CHART_ASAN 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__) || defined(PENUMBRA_CHART_ASAN)
extern "C" const char* __lsan_default_suppressions() {
  return "leak:libfontconfig.so\nleak:libltdl.so\n";
}
#endif

namespace penumbra {

namespace {

// Colour map 0: 0 background, 1 axes and text, 2 grid, then one colour per series (cycled).
constexpr int kBackgroundColor = 0;
constexpr int kForegroundColor = 1;
constexpr int kGridColor = 2;
constexpr int kFirstSeriesColor = 3;
struct RgbBytes {
  int r, g, b;
};
constexpr RgbBytes kSeriesPalette[] = {
    {31, 119, 180}, {214, 39, 40},   {44, 160, 44},   {255, 127, 14}, {148, 103, 189},
    {140, 86, 75},  {227, 119, 194}, {127, 127, 127}, {188, 189, 34}, {23, 190, 207}};
constexpr int kPaletteSize = int(sizeof(kSeriesPalette) / sizeof(kSeriesPalette[0]));
// Marker glyphs (UTF-8; the cairo drivers draw them with the system font).
constexpr const char* kMarkers[] = {"●", "■", "▲", "◆", "▼", "○", "□", "△", "◇", "✕"};
constexpr int kMarkerCount = int(sizeof(kMarkers) / sizeof(kMarkers[0]));
constexpr int kSolidLine = 1;
constexpr int kDashedLine = 2;

std::mutex& plplot_mutex() {
  static std::mutex mutex;
  return mutex;
}

// A value in plotted coordinates, or empty when the axis cannot show it.
std::optional<double> plotted(double value, bool log_axis) {
  if (!std::isfinite(value)) return std::nullopt;
  if (!log_axis) return value;
  if (!(value > 0)) return std::nullopt;
  return std::log10(value);
}

// PLplot treats '#' as the start of an escape sequence; "##" is a literal '#'.
std::string plplot_text(const std::string& text) {
  std::string escaped;
  for (char c : text) {
    escaped += c;
    if (c == '#') escaped += '#';
  }
  return escaped;
}

std::string format_slope(double slope) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.3f", slope);
  return buffer;
}

// One series in plotted coordinates, ready to draw.
struct PlottedSeries {
  std::vector<double> x, y;
  // Error bar ends; an end a log axis cannot show is NaN (drawn to the axis bottom).
  std::vector<double> error_low, error_high;
  std::vector<double> fit_x, fit_y;  // the fitted line's two ends, or empty
};

PlottedSeries plot_series(const ChartSeries& series, bool log_x, bool log_y) {
  if (series.x.size() != series.y.size())
    throw std::invalid_argument("chart series '" + series.name + "' has " +
                                std::to_string(series.x.size()) + " x values but " +
                                std::to_string(series.y.size()) + " y values");
  bool has_errors = !series.y_error.empty();
  if (has_errors && series.y_error.size() != series.y.size())
    throw std::invalid_argument("chart series '" + series.name + "' has " +
                                std::to_string(series.y_error.size()) + " error bars for " +
                                std::to_string(series.y.size()) + " points");
  PlottedSeries out;
  for (size_t i = 0; i < series.x.size(); ++i) {
    auto px = plotted(series.x[i], log_x);
    auto py = plotted(series.y[i], log_y);
    if (!px || !py) continue;
    out.x.push_back(*px);
    out.y.push_back(*py);
    if (has_errors) {
      double half_width = std::abs(series.y_error[i]);
      double nan = std::numeric_limits<double>::quiet_NaN();
      out.error_low.push_back(plotted(series.y[i] - half_width, log_y).value_or(nan));
      out.error_high.push_back(plotted(series.y[i] + half_width, log_y).value_or(*py));
    }
  }
  if (series.fit && !out.x.empty()) {
    double x0 = *std::min_element(out.x.begin(), out.x.end());
    double x1 = *std::max_element(out.x.begin(), out.x.end());
    double y0 = series.fit->intercept + series.fit->slope * x0;
    double y1 = series.fit->intercept + series.fit->slope * x1;
    if (std::isfinite(y0) && std::isfinite(y1)) {
      out.fit_x = {x0, x1};
      out.fit_y = {y0, y1};
    }
  }
  return out;
}

struct Range {
  double low = std::numeric_limits<double>::infinity();
  double high = -std::numeric_limits<double>::infinity();
  void include(double v) {
    if (!std::isfinite(v)) return;
    low = std::min(low, v);
    high = std::max(high, v);
  }
  bool empty() const { return !(low <= high); }
  // Widened by a margin (a fixed one when all values are equal) so no point sits on the frame.
  Range padded(bool log_axis) const {
    double span = high - low;
    double margin = span > 0 ? 0.05 * span : (log_axis ? 0.5 : std::max(0.5, 0.1 * std::abs(low)));
    return Range{low - margin, high + margin};
  }
};

const char* device_for(const std::string& path) {
  std::string extension = std::filesystem::path(path).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  if (extension == ".svg") return "svgcairo";
  if (extension == ".png") return "pngcairo";
  throw std::invalid_argument("chart '" + path + "': unknown extension '" + extension +
                              "' (use .svg or .png)");
}

}  // namespace

LineFit fit_line(const ChartSeries& series, bool log_x, bool log_y) {
  std::vector<double> xs, ys;
  for (size_t i = 0; i < std::min(series.x.size(), series.y.size()); ++i) {
    auto px = plotted(series.x[i], log_x);
    auto py = plotted(series.y[i], log_y);
    if (px && py) {
      xs.push_back(*px);
      ys.push_back(*py);
    }
  }
  if (xs.size() < 2)
    throw std::invalid_argument("fit_line: series '" + series.name + "' has " +
                                std::to_string(xs.size()) + " plottable points, needs 2");
  double n = double(xs.size()), mean_x = 0, mean_y = 0;
  for (size_t i = 0; i < xs.size(); ++i) {
    mean_x += xs[i];
    mean_y += ys[i];
  }
  mean_x /= n;
  mean_y /= n;
  double sxx = 0, sxy = 0;
  for (size_t i = 0; i < xs.size(); ++i) {
    sxx += (xs[i] - mean_x) * (xs[i] - mean_x);
    sxy += (xs[i] - mean_x) * (ys[i] - mean_y);
  }
  if (!(sxx > 0))
    throw std::invalid_argument("fit_line: series '" + series.name + "' has a single x value");
  LineFit fit;
  fit.slope = sxy / sxx;
  fit.intercept = mean_y - fit.slope * mean_x;
  return fit;
}

std::pair<double, double> log_axis_range(double low, double high) {
  if (std::floor(high) - std::ceil(low) >= 1) return {low, high};
  const double snapped_low = std::floor(low);
  return {snapped_low, std::max(std::ceil(high), snapped_low + 1)};
}

void write_line_chart(const std::string& path, const ChartSpec& spec) {
  const char* device = device_for(path);
  if (spec.width < 16 || spec.height < 16 || spec.width > 16384 || spec.height > 16384)
    throw std::invalid_argument("chart '" + path + "': size " + std::to_string(spec.width) + "x" +
                                std::to_string(spec.height) + " outside [16, 16384]");

  // Convert every series and find the plotted ranges.
  std::vector<PlottedSeries> plotted_series;
  Range x_range, y_range;
  for (const ChartSeries& series : spec.series) {
    plotted_series.push_back(plot_series(series, spec.log_x, spec.log_y));
    const PlottedSeries& p = plotted_series.back();
    for (double v : p.x) x_range.include(v);
    for (double v : p.y) y_range.include(v);
    for (double v : p.error_low) y_range.include(v);
    for (double v : p.error_high) y_range.include(v);
    for (double v : p.fit_y) y_range.include(v);
  }
  if (x_range.empty() || y_range.empty())
    throw std::invalid_argument("chart '" + path + "': no point to draw (" +
                                std::to_string(spec.series.size()) + " series)");
  Range x_axis = x_range.padded(spec.log_x), y_axis = y_range.padded(spec.log_y);
  auto two_decades = [](Range& axis) {
    auto [low, high] = log_axis_range(axis.low, axis.high);
    axis.low = low;
    axis.high = high;
  };
  if (spec.log_x) two_decades(x_axis);
  if (spec.log_y) two_decades(y_axis);

  // Make sure the file can be written: PLplot would end the process if it cannot.
  {
    std::ofstream probe(path, std::ios::binary | std::ios::trunc);
    if (!probe) throw std::runtime_error("chart '" + path + "': cannot open the file for writing");
  }

  std::lock_guard<std::mutex> lock(plplot_mutex());
  {
    plstream pls;
    pls.sdev(device);
    pls.sfnam(path.c_str());
    pls.spage(0, 0, spec.width, spec.height, 0, 0);
    pls.scolbg(255, 255, 255);
    pls.scmap0n(kFirstSeriesColor + kPaletteSize);
    pls.init();
    pls.scol0(kBackgroundColor, 255, 255, 255);
    pls.scol0(kForegroundColor, 0, 0, 0);
    pls.scol0(kGridColor, 200, 200, 200);
    for (int i = 0; i < kPaletteSize; ++i)
      pls.scol0(kFirstSeriesColor + i, kSeriesPalette[i].r, kSeriesPalette[i].g,
                kSeriesPalette[i].b);

    // The legend goes right of the plot; leave it room for its longest entry (at the legend's
    // text scale a character is about 5.5 pixels wide on the cairo devices).
    size_t longest_name = 0;
    for (const ChartSeries& series : spec.series)
      longest_name = std::max(longest_name, series.name.size() + (series.fit ? 20 : 0));
    double legend_fraction =
        spec.series.empty() ? 0.0 : std::min(0.5, 0.09 + double(longest_name) * 5.5 / spec.width);
    pls.adv(0);
    pls.vpor(0.1, 0.96 - legend_fraction, 0.12, 0.9);
    pls.wind(x_axis.low, x_axis.high, y_axis.low, y_axis.high);

    // Axes: a light grid, then the frame with ticks and numbers on top ("l": logarithmic).
    std::string log_x = spec.log_x ? "l" : "", log_y = spec.log_y ? "l" : "";
    pls.col0(kGridColor);
    pls.width(0.5);
    pls.box(("g" + log_x).c_str(), 0, 0, ("g" + log_y).c_str(), 0, 0);
    pls.col0(kForegroundColor);
    pls.width(1.0);
    pls.box(("bcnst" + log_x).c_str(), 0, 0, ("bcnstv" + log_y).c_str(), 0, 0);
    pls.lab(plplot_text(spec.x_label).c_str(), plplot_text(spec.y_label).c_str(),
            plplot_text(spec.title).c_str());

    // Series: error bars, lines, markers, fitted lines.
    std::vector<std::string> legend_texts;
    std::vector<PLINT> legend_options, legend_colors, legend_styles;
    std::vector<std::string> legend_symbols;
    for (size_t s = 0; s < spec.series.size(); ++s) {
      const ChartSeries& series = spec.series[s];
      const PlottedSeries& p = plotted_series[s];
      size_t palette_index = series.color >= 0 ? size_t(series.color) : s;
      int color = kFirstSeriesColor + int(palette_index % kPaletteSize);
      const char* marker = kMarkers[palette_index % kMarkerCount];
      int line_style = series.dashed ? kDashedLine : kSolidLine;
      pls.col0(color);
      pls.width(1.5);
      pls.lsty(kSolidLine);
      if (!p.error_low.empty()) {
        std::vector<double> low = p.error_low;
        for (double& v : low)
          if (std::isnan(v)) v = y_axis.low;
        pls.erry(PLINT(p.x.size()), p.x.data(), low.data(), p.error_high.data());
      }
      if (series.lines && p.x.size() >= 2) {
        pls.lsty(line_style);
        pls.line(PLINT(p.x.size()), p.x.data(), p.y.data());
        pls.lsty(kSolidLine);
      }
      if (series.markers && !p.x.empty())
        pls.string(PLINT(p.x.size()), p.x.data(), p.y.data(), marker);

      PLINT option = PL_LEGEND_NONE;
      if (series.lines) option |= PL_LEGEND_LINE;
      if (series.markers) option |= PL_LEGEND_SYMBOL;
      if (option != PL_LEGEND_NONE) option &= ~PL_LEGEND_NONE;
      legend_options.push_back(option);
      legend_texts.push_back(plplot_text(series.name));
      legend_colors.push_back(color);
      legend_styles.push_back(line_style);
      legend_symbols.push_back(marker);

      if (!p.fit_x.empty()) {
        pls.lsty(kDashedLine);
        pls.line(2, p.fit_x.data(), p.fit_y.data());
        pls.lsty(kSolidLine);
        legend_options.push_back(PL_LEGEND_LINE);
        legend_texts.push_back(
            plplot_text(series.name + " fit, slope " + format_slope(series.fit->slope)));
        legend_colors.push_back(color);
        legend_styles.push_back(kDashedLine);
        legend_symbols.push_back("");
      }
    }

    // Legend right of the plot, centred vertically, on a white box.
    if (!legend_texts.empty()) {
      size_t n = legend_texts.size();
      std::vector<const char*> texts, symbols;
      for (size_t i = 0; i < n; ++i) {
        texts.push_back(legend_texts[i].c_str());
        symbols.push_back(legend_symbols[i].c_str());
      }
      std::vector<PLINT> text_colors(n, kForegroundColor), symbol_numbers(n, 1);
      std::vector<PLINT> box_colors(n, 0), box_patterns(n, 0);
      std::vector<PLFLT> box_scales(n, 1.0), box_widths(n, 1.0), line_widths(n, 1.5),
          symbol_scales(n, 1.0);
      PLFLT legend_width = 0, legend_height = 0;
      pls.col0(kForegroundColor);
      pls.legend(&legend_width, &legend_height, PL_LEGEND_BACKGROUND | PL_LEGEND_BOUNDING_BOX,
                 PL_POSITION_RIGHT | PL_POSITION_OUTSIDE, 0.02, 0.0, 0.06, kBackgroundColor,
                 kForegroundColor, kSolidLine, 0, 0, PLINT(n), legend_options.data(), 0.8, 0.7, 2.0,
                 0.0, text_colors.data(), texts.data(), box_colors.data(), box_patterns.data(),
                 box_scales.data(), box_widths.data(), legend_colors.data(), legend_styles.data(),
                 line_widths.data(), legend_colors.data(), symbol_scales.data(),
                 symbol_numbers.data(), symbols.data());
    }
  }  // ~plstream ends the stream and writes the file.

  std::error_code error;
  auto size = std::filesystem::file_size(path, error);
  if (error || size == 0)
    throw std::runtime_error("chart '" + path + "': PLplot produced no output");
}

}  // namespace penumbra
