// The per-region MRSE-against-spp charts of an equal-time batch: each run has one spp level, so
// its points are its curve's, measured by the farm at every sealed pass block for the image and
// for every region; a result written before curves carried regions falls back to one point per
// repeat. Curve regions are read from batch.json, with errors naming their key path.
#include "core/report/batch_charts.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "core/image/metrics.h"

namespace penumbra {
namespace {

// One equal-time method "sa" with two repeats at 16 spp; curve points at 4, 8 and 16 passes whose
// region MRSE is 1 / passes (repeat 0) and 2 / passes (repeat 1) when `with_regions`.
nlohmann::json batch_json(bool with_regions) {
  nlohmann::json runs = nlohmann::json::array();
  for (int repeat = 0; repeat < 2; ++repeat) {
    nlohmann::json curve = nlohmann::json::array();
    for (int passes : {4, 8, 16}) {
      nlohmann::json point = {{"passes", passes},
                              {"compute_seconds", 0.1 * passes},
                              {"wall_seconds", 0.1 * passes},
                              {"mrse", 0.5 / passes}};
      if (with_regions) point["regions"] = {{"shadow", (repeat + 1.0) / passes}};
      curve.push_back(point);
    }
    runs.push_back({{"repeat", repeat},
                    {"seed", repeat},
                    {"exr", "runs/sa.r" + std::to_string(repeat) + ".exr"},
                    {"equal_time", true},
                    {"spp", 16},
                    {"compute_seconds", 1.6},
                    {"curve", curve},
                    {"errors",
                     {{{"region", "image"}, {"mrse", 0.03}, {"mse", 0.1}, {"rmse", 0.3}},
                      {{"region", "shadow"}, {"mrse", 0.1}, {"mse", 0.1}, {"rmse", 0.3}}}}});
  }
  return {{"format", "penumbra/batch-result@1"},
          {"batch_id", "batch-1"},
          {"scene", {{"name", "test"}, {"width", 16}, {"height", 16}}},
          {"regions", {{{"name", "shadow"}, {"rect", {0, 0, 8, 8}}}}},
          {"reference", {{"exr", "reference.exr"}, {"spp", 256}}},
          {"methods",
           {{{"label", "sa"},
             {"method", "sa"},
             {"sampler", "stratified"},
             {"budget_seconds", 1.6},
             {"runs", runs}}}}};
}

RecomputedErrors recomputed_of(const BatchResult& result) {
  RecomputedErrors recomputed(result.methods.size());
  for (size_t m = 0; m < result.methods.size(); ++m)
    for (const BatchRun& run : result.methods[m].runs) recomputed[m].push_back(run.errors);
  return recomputed;
}

TEST(BatchCharts, AnEqualTimeRunsRegionChartIsItsCurve) {
  const BatchResult result = parse_batch_result(batch_json(true).dump());
  ASSERT_EQ(result.methods[0].runs[0].curve[1].regions.at("shadow"), 1.0 / 8);
  const ChartSpec chart = mrse_spp_chart(result, recomputed_of(result), "shadow");
  ASSERT_EQ(chart.series.size(), 1u);
  const ChartSeries& series = chart.series[0];
  EXPECT_EQ(series.x, (std::vector<double>{4, 8, 16}));
  // The mean of the two repeats at each pass count: 1.5 / passes, a slope of exactly -1.
  ASSERT_EQ(series.y.size(), 3u);
  for (size_t i = 0; i < 3; ++i) EXPECT_NEAR(series.y[i], 1.5 / series.x[i], 1e-15) << i;
  ASSERT_TRUE(series.fit.has_value());
  EXPECT_NEAR(series.fit->slope, -1.0, 1e-12);

  // Without region curves: one point per repeat at its spp, no fit.
  const BatchResult older = parse_batch_result(batch_json(false).dump());
  const ChartSeries fallback = mrse_spp_chart(older, recomputed_of(older), "shadow").series[0];
  EXPECT_EQ(fallback.x, (std::vector<double>{16, 16}));
  EXPECT_FALSE(fallback.fit.has_value());
}

TEST(BatchCharts, ABadCurveRegionNamesItsKeyPath) {
  nlohmann::json json = batch_json(true);
  json["methods"][0]["runs"][1]["curve"][2]["regions"]["shadow"] = -1;
  try {
    parse_batch_result(json.dump());
    FAIL() << "a negative region MRSE was accepted";
  } catch (const BatchResultError& error) {
    EXPECT_EQ(error.key_path(), "methods[0].runs[1].curve[2].regions.shadow") << error.what();
  }
  json["methods"][0]["runs"][1]["curve"][2]["regions"] = {1, 2};
  EXPECT_THROW(parse_batch_result(json.dump()), BatchResultError);
}

}  // namespace
}  // namespace penumbra
