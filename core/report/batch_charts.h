#pragma once
// The charts of a batch (core/image/chart.h, PLplot): MRSE against compute time for all methods
// on one log-log chart (from each run's pass-boundary curve), and MRSE against spp with fitted
// log-log slopes (the convergence rate, shown in the legend), for the full image and per region.

#include <filesystem>
#include <string>
#include <vector>

#include "core/image/chart.h"
#include "core/report/batch_result.h"
#include "core/report/batch_table.h"

namespace penumbra {

// MRSE (full image) against compute seconds: one series per method that ran, the mean over the
// runs' curve points at the same pass count (error bars: standard deviation when several runs
// share it). A method without curve points is drawn from its runs' final errors.
ChartSpec mrse_time_chart(const BatchResult& result, const RecomputedErrors& recomputed);

// MRSE of `region` ("image" or a region's name) against spp. Per method: the runs' recomputed
// errors, mean per spp level; when a method has a single spp level and region is "image", the
// curve's points instead (the farm measured them at pass boundaries). A fitted line whenever a
// series has two or more spp values.
ChartSpec mrse_spp_chart(const BatchResult& result, const RecomputedErrors& recomputed,
                         const std::string& region);

struct BatchChartFiles {
  std::string title;
  std::filesystem::path svg, png;
};

// Writes mrse_time, mrse_spp_image and mrse_spp_<region> (file-safe name) as SVG and PNG into
// `chart_dir` (created if needed).
std::vector<BatchChartFiles> write_batch_charts(const BatchResult& result,
                                                const RecomputedErrors& recomputed,
                                                const std::filesystem::path& chart_dir, int width,
                                                int height);

// Letters, digits, '-', '.' and '_' kept; anything else becomes '_'.
std::string file_safe_name(const std::string& name);

}  // namespace penumbra
