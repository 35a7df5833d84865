// A batch end to end on real processes (penumbra-coordinator, one penumbra-worker with one
// thread): equal time by calibration for two methods whose costs differ ~4x (`sa`, `12*sa`: a
// pass also pays for the camera ray and shading, so 12 light samples cost ~4 times one), a
// method the estimator refuses on a GGX scene (`line-bd16`), and the batch result folder of the
// contract (s2_batch_contract.md), written by the client library and by `penumbra batch fetch`,
// read back by the report's reader with the same errors recomputed from the EXRs.
#if __has_include("penumbra/v1/farm.pb.h")
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "core/image/metrics.h"
#include "core/report/batch_result.h"
#include "tests/batch/batch_test_support.h"
#include "tests/farm/farm_test_support.h"

namespace penumbra::farm {
namespace {

using testing::ChildProcess;
using testing::CoordinatorProcess;

const v1::BatchMethodStatus& method_named(const v1::BatchStatus& status, const std::string& label) {
  for (const v1::BatchMethodStatus& method : status.methods())
    if (method.label() == label) return method;
  throw std::runtime_error("no method " + label);
}

const v1::BatchRun& equal_time_run(const v1::BatchMethodStatus& method) {
  for (const v1::BatchRun& run : method.runs())
    if (run.equal_time()) return run;
  throw std::runtime_error("no equal-time run of " + method.label());
}

TEST(BatchFarm, EqualTimeByCalibrationAndTheResultFolder) {
  auto dir = testing::fresh_directory("batch-e2e");
  testing::write_batch_scene(dir);
  CoordinatorProcess coordinator(dir / "data");
  auto worker = testing::start_worker(coordinator.address(), dir, "w1", 1);

  const double budget = 3.0;
  std::string spec = R"({
    "format": "penumbra/batch@1", "name": "e2e", "scene": "batch-test.json",
    "methods": ["sa", {"method": "12*sa", "label": "many-sa"}, "line-bd16"],
    "budget": {"seconds": )" +
                     std::to_string(budget) +
                     R"(, "spp": [4]},
    "reference": {"method": "bsdf+sa", "spp": 64},
    "regions": {"corner": [0, 0, 16, 16]},
    "seed": 3, "repeats": 1})";
  BatchClient client(coordinator.address());
  v1::SubmitBatchResponse response = client.submit(testing::batch_request(dir, spec));
  v1::BatchStatus status = testing::run_to_end(client, response.batch_id());
  ASSERT_EQ(status.state(), v1::BATCH_STATE_DONE) << status.error();

  // Equal time: the two methods' compute seconds agree within 10% though one costs ~4x per pass.
  const v1::BatchRun& sa = equal_time_run(method_named(status, "sa"));
  const v1::BatchRun& many = equal_time_run(method_named(status, "many-sa"));
  double a = sa.job().compute_seconds(), b = many.job().compute_seconds();
  std::printf("equal time: sa %u spp %.3f s, 12*sa %u spp %.3f s (budget %.2f s)\n",
              sa.job().passes_complete(), a, many.job().passes_complete(), b, budget);
  EXPECT_LE(std::abs(a - b), 0.10 * std::max(a, b));
  EXPECT_GT(double(sa.job().passes_complete()), 3.0 * double(many.job().passes_complete()))
      << "the costs per pass should differ ~4x";
  EXPECT_NEAR(a, budget, 0.3 * budget);
  EXPECT_FALSE(sa.job().curve().empty());

  // The refused method: no runs, the estimator's message.
  const v1::BatchMethodStatus& bd16 = method_named(status, "line-bd16");
  EXPECT_EQ(bd16.runs_size(), 0);
  EXPECT_NE(bd16.error().find("line-bd16"), std::string::npos) << bd16.error();

  // The result folder.
  auto result = dir / "result";
  write_batch_result(client, status, result);
  nlohmann::json index = nlohmann::json::parse(std::ifstream(result / "batch.json"));
  EXPECT_EQ(index["format"], "penumbra/batch-result@1");
  EXPECT_EQ(index["batch_id"], response.batch_id());
  EXPECT_EQ(index["name"], "e2e");
  EXPECT_EQ(index["spec"]["seed"], 3);
  EXPECT_EQ(index["scene"]["name"], "batch-test");
  EXPECT_EQ(index["scene"]["width"], 48);
  EXPECT_EQ(index["scene"]["hash"], response.scene_hash());
  std::map<std::string, Region> regions;
  for (const auto& region : index["regions"]) {
    EXPECT_NE(region["name"], "image");
    auto rect = region["rect"].get<std::vector<int>>();
    regions[region["name"]] = Region{rect[0], rect[1], rect[2], rect[3]};
  }
  EXPECT_EQ(regions.size(), 2u);  // the scene's "shadow" and the spec's "corner"
  EXPECT_EQ(index["reference"]["exr"], "reference.exr");
  EXPECT_EQ(index["reference"]["method"], "bsdf+sa");
  EXPECT_EQ(index["reference"]["spp"], 64);
  Image reference = read_exr((result / "reference.exr").string());
  int runs = 0;
  for (const auto& method : index["methods"]) {
    if (method["label"] == "line-bd16") {
      EXPECT_TRUE(method["runs"].empty());
      EXPECT_TRUE(method.contains("error"));
      continue;
    }
    EXPECT_DOUBLE_EQ(method["budget_seconds"].get<double>(), budget);
    ASSERT_EQ(method["runs"].size(), 2u);  // equal time and 4 spp
    for (const auto& run : method["runs"]) {
      ++runs;
      Image image = read_exr((result / run["exr"].get<std::string>()).string());
      auto expected = error_summary(image, reference, regions);
      ASSERT_EQ(run["errors"].size(), expected.size());
      EXPECT_EQ(run["errors"][0]["region"], "image");
      for (const auto& error : run["errors"]) {
        const ErrorSummary& e = expected.at(error["region"]);
        EXPECT_EQ(error["mrse"].get<double>(), e.mrse);
        EXPECT_EQ(error["mse"].get<double>(), e.mse);
        EXPECT_EQ(error["rmse"].get<double>(), e.rmse);
      }
      EXPECT_GT(run["spp"].get<int>(), 0);
      EXPECT_GT(run["compute_seconds"].get<double>(), 0);
      EXPECT_FALSE(run["curve"].empty());
      for (const auto& point : run["curve"]) {
        EXPECT_GT(point["mrse"].get<double>(), 0);
        // Every region, the spec's "corner" too (background: MRSE 0), at every point.
        for (const auto& [name, rect] : regions)
          EXPECT_GE(point["regions"].value(name, -1.0), 0) << name << ": " << point.dump();
        EXPECT_GT(point["regions"].value("shadow", -1.0), 0) << point.dump();
      }
      // The last point is the run's image: its regions' MRSE are the EXR's.
      const auto& last = run["curve"].back();
      if (last["passes"].get<int>() == run["spp"].get<int>()) {
        for (const auto& [name, rect] : regions)
          EXPECT_EQ(last["regions"][name].get<double>(), expected.at(name).mrse) << name;
      }
    }
  }
  EXPECT_EQ(runs, 4);

  // The report's reader accepts it and gets the same errors.
  BatchResult read = read_batch_result(result);
  EXPECT_EQ(read.methods.size(), 3u);

  // The CLI writes the same folder.
  auto fetched = dir / "fetched";
  ChildProcess fetch({testing::binary("client/penumbra"), "batch", "fetch", response.batch_id(),
                      "-o", fetched.string(), "--coordinator", coordinator.address()},
                     (dir / "fetch.log").string());
  EXPECT_EQ(fetch.wait_exit(std::chrono::seconds(60)), 0);
  nlohmann::json again = nlohmann::json::parse(std::ifstream(fetched / "batch.json"));
  EXPECT_EQ(again["methods"], index["methods"]);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace penumbra::farm
#else
#include <gtest/gtest.h>
TEST(FarmNotBuilt, Skipped) {
  GTEST_SKIP() << "configured with PENUMBRA_FARM=OFF";
}
#endif
