#pragma once
// The report of an equal-time comparison batch: a table (table.csv, table.json),
// charts (PLplot, SVG and PNG), a paper-style figure (figure.png, Salesin & Jarosz Figs. 1, 8-10)
// and a self-contained report.html holding all of it, written from a batch result folder
// (core/report/batch_result.h). Every number is recomputed from the EXRs with core/image/metrics.h
// and checked against the errors the batch runner recorded.

#include <filesystem>
#include <optional>
#include <string>

#include "core/report/batch_result.h"

namespace penumbra {

struct BatchReportOptions {
  // Exposure of every tonemapped image in the figure (the same for all columns); empty: chosen
  // from the reference so that its 99th percentile of luminance maps to 0.9.
  std::optional<double> exposure;
  // Width in pixels of one column of the figure (the full image is scaled to it).
  int figure_column_width = 256;
  // A recorded error that differs from the recomputed one by more than this (relative) is a
  // mismatch. Mismatches throw std::runtime_error naming the run and region unless
  // allow_error_mismatch is set; then they are listed in the report's problems section.
  double error_tolerance = 1e-9;
  bool allow_error_mismatch = false;
  // Chart size (pixels for PNG, points for SVG).
  int chart_width = 800, chart_height = 560;
  // Measure every run against this EXR instead of the folder's reference (e.g. a deeper one, to
  // check the table): the recorded errors are then not checked, and the page says so (the farm's
  // MRSE curves stay measured against the folder's reference).
  std::filesystem::path reference_exr;
};

// Reads the batch result folder `result_dir` and writes into `out_dir` (created if needed):
// table.csv, table.json, charts/*.svg and charts/*.png, figure.png and report.html.
// Throws BatchResultError for a malformed batch.json, std::runtime_error for unreadable EXRs,
// images of the wrong size, or recorded errors that do not match the EXRs.
void write_batch_report(const std::filesystem::path& result_dir,
                        const std::filesystem::path& out_dir,
                        const BatchReportOptions& options = {});

}  // namespace penumbra
