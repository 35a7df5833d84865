#pragma once
// The paper-reproduction suite (`penumbra reproduce`): every experiment of the papers we can
// rerun, as one table (experiment, paper figure, paper value, ours, tolerance, status) plus one
// chart per figure and the detailed tables behind the rows.
//
//   Ramamoorthi et al. 2012   Figs. 4, 6, 7 on the visibility function alone
//                             (visibility_reproduction.h); Figs. 8, 13 and 21 in rendered scenes
//                             (pattern_error.h: grids-linear, spheres-plane-{square,disk,gaussian},
//                             thin-fibers).
//   Peters 2021               psa variance and backward error (peters_reproduction.h).
//   Billen & Dutré 2016 Fig. 9, Salesin & Jarosz 2019 Figs. 5, 7: variance slopes of line samples
//                             (variance_convergence.h); "not available" rows while the estimator
//                             refuses line strategies (FormatError), so they turn on by themselves.
//
// Quick mode (the test command) uses fewer trials, pixels and sample counts; full mode is for
// the README's table. Both are deterministic.

#include <functional>
#include <string>
#include <vector>

#include "core/image/chart.h"

namespace penumbra {

// Info: a measurement the papers make no claim about (shown beside a claim it explains); it
// neither passes nor fails.
enum class RowStatus { Pass, Fail, NotAvailable, Info };
std::string_view row_status_name(RowStatus status);  // "PASS", "FAIL", "not available", "info"

struct ReproductionRow {
  std::string experiment;   // what is measured, e.g. "grids-linear: error order, N = 16"
  std::string figure;       // e.g. "Ramamoorthi 2012 Fig. 8"
  std::string paper_value;  // what the paper reports or predicts
  std::string ours;         // what we measured (with its confidence where it is statistical)
  std::string tolerance;    // the pass criterion
  RowStatus status = RowStatus::Fail;
  std::string note;    // why not available, or what the numbers mean
  double seconds = 0;  // wall time of the experiment behind the row (shared rows: 0)
};

struct ReproductionChart {
  std::string name;  // file stem, e.g. "fig8-grids-linear"
  ChartSpec spec;
};

struct ReproductionReport {
  std::string mode;  // "quick" or "full"
  std::vector<ReproductionRow> rows;
  std::vector<ReproductionChart> charts;
  std::vector<std::string> details;  // the detailed text tables, in order
  double seconds = 0;

  bool passed() const;  // no row failed ("not available" and "info" rows do not fail)
};

// The experiments the suite runs, one progress step each.
inline constexpr int kReproductionSteps = 8;

struct ReproductionOptions {
  bool full = false;
  std::string scenes_dir;  // where grids-linear.json etc. live
  int threads = 0;         // 0: the hardware's count
  // Called as each experiment starts with what it reproduces, the experiments done before it and
  // their total (kReproductionSteps), and once more at the end with done == total (may be empty).
  std::function<void(const std::string& what, int done, int total)> progress;
};

// Runs every experiment. Throws only for a broken installation (a scene missing from
// scenes_dir); an experiment that cannot reproduce its figure yields a FAIL row.
ReproductionReport run_reproduction_suite(const ReproductionOptions& options);

// The one table, fixed width, and the detailed tables after it.
std::string format_reproduction_table(const ReproductionReport& report);
// The table as JSON: {"format": "penumbra/reproduce@1", "mode", "seconds", "passed", "rows":
// [...]}.
std::string reproduction_json(const ReproductionReport& report);
// Writes every chart as DIR/<name>.svg and DIR/<name>.png (creating DIR); returns the paths.
std::vector<std::string> write_reproduction_charts(const ReproductionReport& report,
                                                   const std::string& dir);

}  // namespace penumbra
