#pragma once
// report.html of a batch: one self-contained page (no network): the table, the comparison viewer
// (comparison_viewer.h, the page's only script), the charts
// (SVG inlined as data: URIs), the figure (PNG as a data: URI), the references and refusals, the
// spec as submitted, and any problems found while checking the result.

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "core/report/batch_charts.h"
#include "core/report/batch_comparison.h"
#include "core/report/batch_figure.h"
#include "core/report/batch_result.h"
#include "core/report/batch_table.h"

namespace penumbra {

struct BatchReportContent {
  const BatchResult* result = nullptr;
  const BatchTable* table = nullptr;
  std::vector<BatchChartFiles> charts;  // files are read and inlined; paths shown relative to out
  std::filesystem::path figure_png;     // inlined
  BatchFigureInfo figure;
  std::vector<std::string> problems;            // e.g. recorded errors that do not match the EXRs
  std::filesystem::path out_dir;                // for the relative links to table.csv, PNG charts
  const BatchComparison* comparison = nullptr;  // pairwise comparisons, the baseline
  const ReferenceNoise* reference_noise = nullptr;  // the reference's own noise per region
  std::string viewer_html;  // the comparison viewer's section (comparison_viewer.h), or empty
};

std::string batch_report_html(const BatchReportContent& content);

std::string html_escape(std::string_view text);
std::string base64_encode(std::string_view bytes);

}  // namespace penumbra
