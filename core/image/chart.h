#pragma once
// Line charts (convergence plots, error tables) drawn with PLplot's cairo drivers: SVG or PNG,
// chosen by the file's extension.

#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace penumbra {

// A straight line in the chart's plotted coordinates: log10 of a value on a logarithmic axis,
// the value itself on a linear one. On a log-log chart the slope is the convergence rate.
struct LineFit {
  double slope = 0;
  double intercept = 0;
};

struct ChartSeries {
  std::string name;
  std::vector<double> x, y;
  // Symmetric error bars (half widths, same length as y), or empty for none.
  std::vector<double> y_error;
  // A fitted line drawn dashed over the series' x range; its slope is shown in the legend.
  std::optional<LineFit> fit;
  bool markers = true;  // draw a symbol at each point
  bool lines = true;    // connect the points
  bool dashed = false;  // draw the connecting line dashed (e.g. a predicted curve)
  int color = -1;       // palette index (cycled); -1: the series' position in the chart
};

struct ChartSpec {
  std::string title;
  std::string x_label, y_label;
  bool log_x = false, log_y = false;
  std::vector<ChartSeries> series;
  int width = 800, height = 600;  // pixels for PNG; points for SVG
};

// Least-squares line through a series' points in plotted coordinates (points that a log axis
// cannot show are skipped). Throws std::invalid_argument with fewer than 2 usable points.
LineFit fit_line(const ChartSeries& series, bool log_x, bool log_y);

// The drawn range of a logarithmic axis whose padded data range is [low, high] in log10: PLplot
// labels such an axis at its decades only, so a range holding fewer than two decades is widened
// to the decades around it (every log axis gets at least two labels).
std::pair<double, double> log_axis_range(double low, double high);

// Writes the chart to `path` (".svg" or ".png"). Points a logarithmic axis cannot show (<= 0)
// and non-finite values are left out. Thread-safe (PLplot keeps global state; calls are
// serialized). Throws std::invalid_argument for an unknown extension or a chart with nothing
// to draw, std::runtime_error naming the path when the file cannot be written.
void write_line_chart(const std::string& path, const ChartSpec& spec);

}  // namespace penumbra
