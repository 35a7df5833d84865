// write_batch_report: read and check the result folder, then write the table, charts, figure and
// page.

#include "core/report/batch_report.h"

#include <fstream>
#include <stdexcept>

#include "core/report/batch_charts.h"
#include "core/report/batch_comparison.h"
#include "core/report/batch_figure.h"
#include "core/report/batch_html.h"
#include "core/report/batch_table.h"
#include "core/report/comparison_viewer.h"

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

// The viewer's content: the reference and, per method that ran, the run the figure shows with its
// own MRSE and its table row's corrected MRSE. `images` holds the pixels the content points to.
ComparisonViewerContent viewer_content(const BatchResult& result, const BatchTable& table,
                                       const RecomputedErrors& recomputed,
                                       const BatchFigureInfo& figure,
                                       const std::filesystem::path& result_dir,
                                       std::vector<Image>& images, std::vector<Image>& variances) {
  ComparisonViewerContent content;
  images.clear();
  variances.clear();
  images.reserve(result.methods.size() + 1);
  variances.reserve(result.methods.size() + 1);
  variances.emplace_back();
  images.push_back(read_exr((result_dir / result.reference.exr).string(), nullptr, &variances[0]));
  content.width = images[0].width;
  content.height = images[0].height;
  content.reference.label = "reference";
  content.reference.method = result.reference.method;
  content.reference.sampler = result.reference.sampler;
  content.reference.spp = result.reference.spp;
  for (const BatchRegion& region : result.regions)
    content.regions.push_back({region.name, region.rect});
  struct Shown {
    size_t method, run;
  };
  std::vector<Shown> shown;
  for (size_t m = 0; m < result.methods.size(); ++m) {
    int run = m < figure.shown_runs.size() ? figure.shown_runs[m] : -1;
    if (run < 0) continue;
    shown.push_back({m, size_t(run)});
    variances.emplace_back();
    images.push_back(read_exr((result_dir / result.methods[m].runs[size_t(run)].exr).string(),
                              nullptr, &variances.back()));
  }
  // A file without a variance layer reads as a 0x0 variance: the viewer says it has none.
  auto variance_of = [&](size_t index) -> const Image* {
    return variances[index].width ? &variances[index] : nullptr;
  };
  content.reference.image = &images[0];
  content.reference.variance = variance_of(0);
  for (size_t i = 0; i < shown.size(); ++i) {
    const BatchMethod& method = result.methods[shown[i].method];
    const BatchRun& run = method.runs[shown[i].run];
    ViewerImage image;
    image.label = method.label;
    image.method = method.method;
    image.sampler = method.sampler;
    image.spp = run.spp;
    image.repeat = run.repeat;
    image.compute_seconds = run.compute_seconds;
    image.image = &images[i + 1];
    image.variance = variance_of(i + 1);
    for (const auto& [region, summary] : recomputed[shown[i].method][shown[i].run])
      image.mrse[region] = summary.mrse;
    for (const BatchTableRow& row : table.rows) {
      if (row.method_index != shown[i].method) continue;
      bool has_run = false;
      for (size_t index : row.run_indices) has_run = has_run || index == shown[i].run;
      if (!has_run) continue;
      for (const auto& [region, cell] : row.cells) image.corrected[region] = cell.corrected;
      image.repeats = row.repeats;
    }
    content.methods.push_back(std::move(image));
  }
  // The same scales as the coordinator's batch page; the exposure and error scale are the
  // figure's (its exposure may be given on the command line).
  choose_viewer_scales(content);
  content.exposure = figure.exposure;
  content.error_scale = figure.error_scale;
  return content;
}

}  // namespace

void write_batch_report(const std::filesystem::path& result_dir,
                        const std::filesystem::path& out_dir, const BatchReportOptions& options) {
  BatchResult result = read_batch_result(result_dir);
  const bool replaced = !options.reference_exr.empty();
  if (replaced) result.reference.exr = std::filesystem::absolute(options.reference_exr).string();
  RecomputedErrors recomputed = recompute_batch_errors(result, result_dir);

  // The recorded errors must be the ones the EXRs give (against the folder's own reference).
  std::vector<std::string> mismatches;
  if (replaced)
    mismatches.push_back("every error is measured against " + result.reference.exr +
                         " instead of the folder's reference; the recorded errors were not "
                         "checked and the MRSE curves were recorded against the folder's");
  else
    mismatches = compare_recorded_errors(result, recomputed, options.error_tolerance);
  if (!replaced && !mismatches.empty() && !options.allow_error_mismatch) {
    std::string message = (result_dir / "batch.json").string() + ": " +
                          std::to_string(mismatches.size()) +
                          " recorded error(s) differ from the EXRs:";
    for (const std::string& mismatch : mismatches) message += "\n  " + mismatch;
    throw std::runtime_error(message);
  }

  std::filesystem::create_directories(out_dir);
  BatchTable table = make_batch_table(result, recomputed);
  const ReferenceNoise noise = read_reference_noise(result, result_dir);
  const BatchComparison comparison = compare_batch_rows(table, result, recomputed, noise);
  write_text_file(out_dir / "table.csv", batch_table_csv(table));
  nlohmann::json table_json = batch_table_json(table);
  add_comparison_json(table_json, table, comparison, noise);
  if (result.reference.sizing) {
    const BatchReferenceSizing& sizing = *result.reference.sizing;
    table_json["reference_sizing"] = {{"spp", result.reference.spp},
                                      {"required_spp", sizing.required_spp},
                                      {"capped", sizing.capped},
                                      {"target_share", sizing.target_share},
                                      {"max_seconds", sizing.max_seconds},
                                      {"predicted_share", sizing.predicted_share},
                                      {"deciding_region", sizing.deciding_region},
                                      {"text", reference_sizing_text(result.reference)}};
  }
  write_text_file(out_dir / "table.json", table_json.dump(2) + "\n");

  BatchReportContent content;
  content.result = &result;
  content.table = &table;
  content.out_dir = out_dir;
  content.problems = mismatches;
  if (std::string warning = reference_depth_warning(result); !warning.empty())
    content.problems.push_back(warning);
  content.comparison = &comparison;
  content.reference_noise = &noise;
  // The charts draw corrected MRSE (the reference's term removed from every point).
  content.charts = write_batch_charts(
      corrected_curves(result, noise), corrected_errors(recomputed, noise), out_dir / "charts",
      options.chart_width, options.chart_height, chart_annotations(table, noise));
  content.figure_png = out_dir / "figure.png";
  content.figure = write_batch_figure(result, recomputed, result_dir, content.figure_png, options);
  {
    std::vector<Image> images, variances;
    content.viewer_html = comparison_viewer_html(
        viewer_content(result, table, recomputed, content.figure, result_dir, images, variances));
  }
  write_text_file(out_dir / "report.html", batch_report_html(content));
}

}  // namespace penumbra
