// write_batch_report: read and check the result folder, then write the table, charts, figure and
// page.

#include "core/report/batch_report.h"

#include <fstream>
#include <stdexcept>

#include "core/report/batch_charts.h"
#include "core/report/batch_figure.h"
#include "core/report/batch_html.h"
#include "core/report/batch_table.h"

namespace penumbra {

namespace {

void write_text_file(const std::filesystem::path& path, const std::string& text) {
  std::filesystem::path temporary = path;
  temporary += ".tmp";
  {
    std::ofstream file(temporary, std::ios::binary | std::ios::trunc);
    if (!file) throw std::runtime_error(path.string() + ": cannot write");
    file << text;
    if (!file.flush()) throw std::runtime_error(path.string() + ": write failed");
  }
  std::filesystem::rename(temporary, path);
}

}  // namespace

void write_batch_report(const std::filesystem::path& result_dir,
                        const std::filesystem::path& out_dir, const BatchReportOptions& options) {
  BatchResult result = read_batch_result(result_dir);
  RecomputedErrors recomputed = recompute_batch_errors(result, result_dir);

  // The recorded errors must be the ones the EXRs give.
  std::vector<std::string> mismatches =
      compare_recorded_errors(result, recomputed, options.error_tolerance);
  if (!mismatches.empty() && !options.allow_error_mismatch) {
    std::string message = (result_dir / "batch.json").string() + ": " +
                          std::to_string(mismatches.size()) +
                          " recorded error(s) differ from the EXRs:";
    for (const std::string& mismatch : mismatches) message += "\n  " + mismatch;
    throw std::runtime_error(message);
  }

  std::filesystem::create_directories(out_dir);
  BatchTable table = make_batch_table(result, recomputed);
  write_text_file(out_dir / "table.csv", batch_table_csv(table));
  write_text_file(out_dir / "table.json", batch_table_json(table).dump(2) + "\n");

  BatchReportContent content;
  content.result = &result;
  content.table = &table;
  content.out_dir = out_dir;
  content.problems = mismatches;
  content.charts = write_batch_charts(result, recomputed, out_dir / "charts", options.chart_width,
                                      options.chart_height);
  content.figure_png = out_dir / "figure.png";
  content.figure = write_batch_figure(result, recomputed, result_dir, content.figure_png, options);
  write_text_file(out_dir / "report.html", batch_report_html(content));
}

}  // namespace penumbra
