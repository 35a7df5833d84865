// The batch's charts: series built from the batch result and the recomputed errors, drawn with
// core/image/chart.h.

#include "core/report/batch_charts.h"

#include <map>
#include <set>

namespace penumbra {

namespace {

// Points grouped by x (mean x and y of each group, the 95% interval of the mean y as error bar).
struct GroupedPoints {
  std::map<uint32_t, std::vector<double>> x, y;
  void add(uint32_t key, double x_value, double y_value) {
    x[key].push_back(x_value);
    y[key].push_back(y_value);
  }
  ChartSeries series(const std::string& name) const {
    ChartSeries series;
    series.name = name;
    bool any_spread = false;
    for (const auto& [key, ys] : y) {
      series.x.push_back(mean_std(x.at(key)).mean);
      MeanInterval stats = mean_interval(ys);
      series.y.push_back(stats.mean);
      series.y_error.push_back(stats.half_width);
      any_spread = any_spread || stats.has_interval;
    }
    if (!any_spread) series.y_error.clear();
    return series;
  }
};

// A fitted log-log line when the series has two or more distinct positive points.
void add_fit(ChartSeries& series) {
  std::set<double> xs;
  for (size_t i = 0; i < series.x.size(); ++i)
    if (series.x[i] > 0 && series.y[i] > 0) xs.insert(series.x[i]);
  if (xs.size() >= 2) series.fit = fit_line(series, true, true);
}

}  // namespace

std::string ChartAnnotations::suffix(const std::string& label, const std::string& region) const {
  auto it = legend_suffix.find({label, region});
  return it == legend_suffix.end() ? "" : it->second;
}

ChartSpec mrse_time_chart(const BatchResult& result, const RecomputedErrors& recomputed,
                          const ChartAnnotations& annotations) {
  ChartSpec spec;
  spec.title = "MRSE against compute time" + (result.name.empty() ? "" : ": " + result.name);
  spec.x_label = "compute seconds";
  spec.y_label = "MRSE (full image)" + annotations.y_label_note;
  spec.log_x = spec.log_y = true;
  for (size_t m = 0; m < result.methods.size(); ++m) {
    const BatchMethod& method = result.methods[m];
    if (method.runs.empty()) continue;
    GroupedPoints points;
    for (size_t r = 0; r < method.runs.size(); ++r) {
      const BatchRun& run = method.runs[r];
      if (run.curve.empty()) {
        points.add(run.spp, run.compute_seconds, recomputed.at(m).at(r).at("image").mrse);
        continue;
      }
      for (const BatchCurvePoint& point : run.curve)
        points.add(point.passes, point.compute_seconds, point.mrse);
    }
    ChartSeries series = points.series(method.label + annotations.suffix(method.label, "image"));
    series.color = int(m);
    spec.series.push_back(std::move(series));
  }
  return spec;
}

ChartSpec mrse_spp_chart(const BatchResult& result, const RecomputedErrors& recomputed,
                         const std::string& region, const ChartAnnotations& annotations) {
  ChartSpec spec;
  spec.title =
      "MRSE against spp, " + (region == "image" ? std::string("full image") : "region " + region);
  spec.x_label = "samples per pixel";
  spec.y_label = "MRSE (" + region + ")" + annotations.y_label_note;
  spec.log_x = spec.log_y = true;
  for (size_t m = 0; m < result.methods.size(); ++m) {
    const BatchMethod& method = result.methods[m];
    if (method.runs.empty()) continue;
    std::set<uint32_t> spp_levels;
    for (const BatchRun& run : method.runs) spp_levels.insert(run.spp);
    GroupedPoints points;
    if (spp_levels.size() == 1) {
      // One spp level (an equal-time run): the farm's curve, measured at every sealed pass
      // block, for the image and for each region (results written before the curve carried
      // regions have none there).
      for (const BatchRun& run : method.runs)
        for (const BatchCurvePoint& point : run.curve) {
          if (region == "image") {
            points.add(point.passes, double(point.passes), point.mrse);
          } else if (auto it = point.regions.find(region); it != point.regions.end()) {
            points.add(point.passes, double(point.passes), it->second);
          }
        }
    }
    // A region of a method with one spp level and no region curve: each repeat is its own
    // point (its spp and its error), not one mean.
    const bool per_repeat = spp_levels.size() == 1 && points.y.empty();
    if (points.y.empty()) {
      for (size_t r = 0; r < method.runs.size(); ++r)
        points.add(per_repeat ? uint32_t(r) : method.runs[r].spp, double(method.runs[r].spp),
                   recomputed.at(m).at(r).at(region).mrse);
    }
    ChartSeries series = points.series(method.label + annotations.suffix(method.label, region));
    series.color = int(m);
    if (per_repeat) {
      series.lines = false;
      series.y_error.clear();
    } else {
      add_fit(series);
    }
    spec.series.push_back(std::move(series));
  }
  return spec;
}

std::string file_safe_name(const std::string& name) {
  std::string safe;
  for (char c : name) {
    bool keep = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                c == '-' || c == '.' || c == '_';
    safe += keep ? c : '_';
  }
  return safe.empty() ? "_" : safe;
}

std::vector<BatchChartFiles> write_batch_charts(const BatchResult& result,
                                                const RecomputedErrors& recomputed,
                                                const std::filesystem::path& chart_dir, int width,
                                                int height, const ChartAnnotations& annotations) {
  std::filesystem::create_directories(chart_dir);
  std::vector<std::pair<std::string, ChartSpec>> charts;
  charts.emplace_back("mrse_time", mrse_time_chart(result, recomputed, annotations));
  charts.emplace_back("mrse_spp_image", mrse_spp_chart(result, recomputed, "image", annotations));
  std::set<std::string> stems = {"mrse_time", "mrse_spp_image"};
  for (const BatchRegion& region : result.regions) {
    std::string stem = "mrse_spp_region_" + file_safe_name(region.name);
    while (!stems.insert(stem).second) stem += "_";
    charts.emplace_back(stem, mrse_spp_chart(result, recomputed, region.name, annotations));
  }
  std::vector<BatchChartFiles> files;
  for (auto& [stem, spec] : charts) {
    if (spec.series.empty()) continue;  // every method refused: nothing to chart
    spec.width = width;
    spec.height = height;
    BatchChartFiles file{spec.title, chart_dir / (stem + ".svg"), chart_dir / (stem + ".png")};
    write_line_chart(file.svg.string(), spec);
    write_line_chart(file.png.string(), spec);
    files.push_back(std::move(file));
  }
  return files;
}

}  // namespace penumbra
