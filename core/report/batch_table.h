#pragma once
// The table of a batch: one row per method and spp level (per method when it ran on a time
// budget), with compute seconds and MRSE of the full image and each region, mean and standard
// deviation over repeats. Every MRSE is recomputed from the EXRs (core/image/metrics.h) and the
// recorded errors are checked against it.

#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "core/image/metrics.h"
#include "core/report/batch_result.h"
#include "core/report/significance.h"

namespace penumbra {

// error_summary of each run's EXR against the reference: [method][run] -> region -> summary.
using RecomputedErrors = std::vector<std::vector<std::map<std::string, ErrorSummary>>>;

// Reads reference.exr and every run's EXR once. Throws std::runtime_error naming the file when
// one cannot be read or its size differs from the scene's.
RecomputedErrors recompute_batch_errors(const BatchResult& result,
                                        const std::filesystem::path& result_dir);

// "methods[1].runs[0] (label, repeat 0): region "penumbra": mrse recorded 0.3, recomputed
// 0.31 (relative difference 3.2e-2)" for every recorded value that differs from the recomputed one
// by more than `relative_tolerance` of the larger magnitude.
std::vector<std::string> compare_recorded_errors(const BatchResult& result,
                                                 const RecomputedErrors& recomputed,
                                                 double relative_tolerance);

struct MeanStd {
  double mean = 0;
  double std = 0;  // sample standard deviation (n - 1); 0 for a single value
  int count = 0;
};
MeanStd mean_std(const std::vector<double>& values);

// One region of one row, filled by compare_batch_rows (core/report/batch_comparison.h).
struct BatchCell {
  MeanInterval corrected;          // noise-corrected MRSE over the repeats, 95% interval with the
                                   // reference's shared deviation
  MeanInterval plain;              // the MRSE as measured (interval from the repeats' spread alone)
  double reference_share = 0;      // mean over the runs of the reference's term / plain MRSE
  bool reference_flagged = false;  // reference_share > kReferenceShareFlag
};

struct BatchTableRow {
  std::string label, method, sampler;
  std::optional<double> budget_seconds;
  std::string refusal;  // non-empty: the farm refused the method; no numbers
  uint32_t spp_min = 0, spp_max = 0;
  int repeats = 0;  // runs in the row
  MeanStd compute_seconds;
  std::map<std::string, MeanStd> mrse;  // "image" and every region
  // Rows compared with each other for "best": the same budget, or the same spp.
  std::string comparison_group;
  // Columns where this row is the best of its group ("mrse:image", "mrse:<region>"); only in
  // groups of two or more rows. make_batch_table marks the lowest mean; compare_batch_rows
  // keeps only the rows that beat every other row of the group at 95%.
  std::set<std::string> best;
  std::map<std::string, BatchCell> cells;  // "image" and every region (compare_batch_rows)
  // 1 / (MRSE x compute seconds) relative to the baseline's (paired by repeat, image MRSE
  // corrected); count 0 when not measured (no baseline row in the group, an MRSE <= 0).
  MeanInterval efficiency;
  // The runs of the row: indices into the method's runs.
  size_t method_index = 0;
  std::vector<size_t> run_indices;
};

struct BatchTable {
  std::vector<std::string> regions;  // "image" first, then the batch's regions in order
  std::vector<BatchTableRow> rows;
};

BatchTable make_batch_table(const BatchResult& result, const RecomputedErrors& recomputed);

// The table as CSV (header row, then one row per table row; refusals have empty numbers) and as
// JSON ({"regions": [...], "rows": [...]}).
std::string batch_table_csv(const BatchTable& table);
nlohmann::json batch_table_json(const BatchTable& table);

// Numbers as the report prints them: 4 significant digits, "1.234e-05" below 1e-3.
std::string format_number(double value);

}  // namespace penumbra
