// The batch table's marks in an equal-time group: the methods share one compute budget, so only
// the MRSE columns can have a best row; the compute seconds (all near the budget) never do.
#include "core/report/batch_table.h"

#include <gtest/gtest.h>

namespace penumbra {
namespace {

BatchMethod budget_method(const std::string& label, std::vector<double> seconds,
                          std::vector<double> mrse, RecomputedErrors& recomputed) {
  BatchMethod method;
  method.label = label;
  method.method = label;
  method.sampler = "stratified";
  method.budget_seconds = 2.0;
  recomputed.emplace_back();
  for (size_t r = 0; r < seconds.size(); ++r) {
    BatchRun run;
    run.repeat = int(r);
    run.spp = 10;
    run.equal_time = true;  // the method's equal-time runs (not spp-level ones)
    run.compute_seconds = seconds[r];
    method.runs.push_back(run);
    ErrorSummary error;
    error.mrse = mrse[r];
    recomputed.back().push_back({{"image", error}, {"shadow", error}});
  }
  return method;
}

TEST(BatchTable, AnEqualTimeGroupMarksTheLowestMrseNeverTheLowestComputeSeconds) {
  BatchResult result;
  result.regions.push_back({"shadow", Region{0, 0, 4, 4}});
  RecomputedErrors recomputed;
  // "quick" spent the least compute time but has the larger error.
  result.methods.push_back(
      budget_method("quick", {1.80, 1.85, 1.90}, {0.30, 0.32, 0.31}, recomputed));
  result.methods.push_back(
      budget_method("clean", {2.10, 2.20, 2.15}, {0.10, 0.11, 0.12}, recomputed));
  const BatchTable table = make_batch_table(result, recomputed);
  ASSERT_EQ(table.rows.size(), 2u);
  EXPECT_EQ(table.rows[0].comparison_group, "budget 2 s");
  EXPECT_EQ(table.rows[0].comparison_group, table.rows[1].comparison_group);
  EXPECT_TRUE(table.rows[0].best.empty()) << "the quicker row was marked";
  EXPECT_EQ(table.rows[1].best, (std::set<std::string>{"mrse:image", "mrse:shadow"}));
  const nlohmann::json json = batch_table_json(table);
  for (const nlohmann::json& row : json["rows"])
    for (const nlohmann::json& column : row["best"])
      EXPECT_EQ(column.get<std::string>().rfind("mrse:", 0), 0u) << column;
}

}  // namespace
}  // namespace penumbra
