#pragma once
// The charts of a batch (core/image/chart.h, PLplot): MRSE against compute time for all methods
// on one log-log chart (from each run's pass-boundary curve), and MRSE against spp with fitted
// log-log slopes (the convergence rate, shown in the legend), for the full image and per region.

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "core/image/chart.h"
#include "core/report/batch_result.h"
#include "core/report/batch_table.h"

namespace penumbra {

// What the charts add to the plain picture (core/report/batch_comparison.h): a note after the
// y axis label ("corrected") and, per method label and region, a suffix of its legend entry
// (a flag when the reference is more than 10% of its error there).
struct ChartAnnotations {
  std::string y_label_note;
  std::map<std::pair<std::string, std::string>, std::string> legend_suffix;  // (label, region)
  std::string suffix(const std::string& label, const std::string& region) const;
};

// MRSE (full image) against compute seconds: one series per method that ran, the mean over the
// runs' curve points at the same pass count (error bars: the 95% interval of that mean when
// several runs share it). A method without curve points is drawn from its runs' final errors.
ChartSpec mrse_time_chart(const BatchResult& result, const RecomputedErrors& recomputed,
                          const ChartAnnotations& annotations = {});

// MRSE of `region` ("image" or a region's name) against spp. Per method: the runs' recomputed
// errors, mean per spp level; when a method has a single spp level, the curve's points instead
// (the farm measured the image and every region at pass boundaries), or one point per repeat
// for a region the curve lacks (results written before curves carried regions). A fitted line
// whenever a series of means has two or more spp values.
ChartSpec mrse_spp_chart(const BatchResult& result, const RecomputedErrors& recomputed,
                         const std::string& region, const ChartAnnotations& annotations = {});

struct BatchChartFiles {
  std::string title;
  std::filesystem::path svg, png;
};

// Writes mrse_time, mrse_spp_image and mrse_spp_<region> (file-safe name) as SVG and PNG into
// `chart_dir` (created if needed).
std::vector<BatchChartFiles> write_batch_charts(const BatchResult& result,
                                                const RecomputedErrors& recomputed,
                                                const std::filesystem::path& chart_dir, int width,
                                                int height,
                                                const ChartAnnotations& annotations = {});

// Letters, digits, '-', '.' and '_' kept; anything else becomes '_'.
std::string file_safe_name(const std::string& name);

}  // namespace penumbra
