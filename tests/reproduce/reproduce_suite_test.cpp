// The quick paper-reproduction suite (core/analysis/reproduction_suite.h), run through the
// analysis API: the test fails when any figure is not reproduced (a FAIL row). "not available"
// rows (line strategies before they land) do not fail, but must say why. The whole table is
// printed so a failing run shows what was measured.

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "core/analysis/reproduction_suite.h"

namespace penumbra {
namespace {

TEST(ReproductionSuite, QuickModeReproducesEveryFigure) {
  ReproductionOptions options;
  options.full = false;
  options.scenes_dir = std::string(PENUMBRA_SOURCE_DIR) + "/scenes";
  int steps = 0;
  options.progress = [&](const std::string& line, int done, int total) {
    EXPECT_EQ(done, steps++) << line;
    EXPECT_EQ(total, kReproductionSteps);
    std::printf("[ reproduce ] %d/%d %s\n", done, total, line.c_str());
  };
  ReproductionReport report = run_reproduction_suite(options);
  EXPECT_EQ(steps, kReproductionSteps + 1);  // each experiment, then the end
  std::printf("%s\n", format_reproduction_table(report).c_str());

  ASSERT_FALSE(report.rows.empty());
  int reproduced = 0;
  for (const ReproductionRow& row : report.rows) {
    EXPECT_NE(row.status, RowStatus::Fail)
        << row.figure << ": " << row.experiment << "\n  paper: " << row.paper_value
        << "\n  ours: " << row.ours << "\n  tolerance: " << row.tolerance;
    if (row.status == RowStatus::NotAvailable) {
      EXPECT_FALSE(row.note.empty()) << row.experiment << ": a not-available row must say why";
    }
    reproduced += row.status == RowStatus::Pass;
  }
  EXPECT_TRUE(report.passed());
  EXPECT_GT(reproduced, 20);
  // The figures that must always be there: Ramamoorthi Figs. 4, 6, 7, 8, 13, 21 and Peters.
  for (const char* figure :
       {"Fig. 4", "Fig. 6", "Fig. 7a", "Fig. 7b", "Fig. 8", "Fig. 13", "Fig. 21", "Peters 2021"}) {
    bool found = false;
    for (const ReproductionRow& row : report.rows)
      found =
          found || (row.figure.find(figure) != std::string::npos && row.status == RowStatus::Pass);
    EXPECT_TRUE(found) << "no passing row for " << figure;
  }

  // The outputs the command writes: JSON with every row, and one chart per figure.
  nlohmann::json doc = nlohmann::json::parse(reproduction_json(report));
  EXPECT_EQ(doc["format"], "penumbra/reproduce@1");
  EXPECT_EQ(doc["rows"].size(), report.rows.size());
  std::filesystem::path dir = std::filesystem::path(PENUMBRA_BINARY_DIR) / "reproduce-test-out";
  std::filesystem::remove_all(dir);
  std::vector<std::string> paths = write_reproduction_charts(report, dir.string());
  EXPECT_EQ(paths.size(), 2 * report.charts.size());
  for (const std::string& path : paths) {
    ASSERT_TRUE(std::filesystem::exists(path)) << path;
    EXPECT_GT(std::filesystem::file_size(path), 1000u) << path;
  }
}

}  // namespace
}  // namespace penumbra
