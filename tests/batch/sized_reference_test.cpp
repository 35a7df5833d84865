// A sized auto reference ("spp": "auto") end to end on real processes: the coordinator probes
// every method and the reference method, sizes the reference, renders it, and the result folder
// says what it chose. The prediction is checked against what the batch then measured: the
// reference's realised term over the best method's corrected MRSE, in the region that decided
// the size, is the target share up to the probes' accuracy (within a factor 3 either way).
#if __has_include("penumbra/v1/farm.pb.h")
#include <gtest/gtest.h>

#include <cmath>

#include "core/image/image.h"
#include "core/image/noise_corrected_mrse.h"
#include "core/report/batch_result.h"
#include "tests/batch/batch_test_support.h"
#include "tests/farm/farm_test_support.h"

namespace penumbra::farm {
namespace {

using testing::CoordinatorProcess;

TEST(SizedReference, ProbesSizeTheReferenceToItsTargetShare) {
  auto dir = testing::fresh_directory("sized-reference");
  testing::write_batch_scene(dir, 32);
  CoordinatorProcess coordinator(dir / "data");
  auto worker = testing::start_worker(coordinator.address(), dir, "w1", 2);
  const double target = 0.05;
  const std::string spec = R"({
    "format": "penumbra/batch@1", "name": "sized", "scene": "batch-test.json",
    "methods": ["sa", "area"], "budget": {"spp": [8]},
    "reference": {"method": "bsdf+sa", "spp": "auto", "target_share": 0.05, "max_seconds": 120},
    "seed": 5, "repeats": 2})";
  BatchClient client(coordinator.address());
  v1::SubmitBatchResponse response = client.submit(testing::batch_request(dir, spec));
  v1::BatchStatus status = testing::run_to_end(client, response.batch_id());
  ASSERT_EQ(status.state(), v1::BATCH_STATE_DONE) << status.error();
  const v1::BatchReferenceStatus& reference = status.reference();
  ASSERT_TRUE(reference.sizing().sized());
  EXPECT_EQ(reference.sizing().probe_jobs_size(), 3);  // two methods, then the reference method
  EXPECT_FALSE(reference.sizing().capped());
  EXPECT_GT(reference.spp(), 8u);
  EXPECT_GE(double(reference.spp()), reference.sizing().required_spp());
  EXPECT_LE(reference.sizing().predicted_share(), target / (1 + target) * (1 + 1e-9));

  const auto out = dir / "result";
  write_batch_result(client, status, out);
  const BatchResult result = read_batch_result(out);
  ASSERT_TRUE(result.reference.sizing.has_value());
  EXPECT_EQ(result.reference.spp, reference.spp());
  EXPECT_NE(reference_sizing_text(result.reference).find(std::to_string(reference.spp()) + " spp"),
            std::string::npos)
      << reference_sizing_text(result.reference);

  // What the batch measured in the deciding region: the reference's term over the best
  // method's corrected MRSE (mean over its repeats).
  const std::string region_name = result.reference.sizing->deciding_region;
  Region region{0, 0, result.scene.width, result.scene.height};
  for (const BatchRegion& r : result.regions)
    if (r.name == region_name) region = r.rect;
  Image variance;
  const Image deep = read_exr((out / result.reference.exr).string(), nullptr, &variance);
  ASSERT_GT(variance.width, 0);
  double best = 0;
  for (const BatchMethod& method : result.methods) {
    double corrected = 0;
    for (const BatchRun& run : method.runs)
      corrected += noise_corrected_mrse(read_exr((out / run.exr).string()), deep, variance, region)
                       .corrected;
    corrected /= double(method.runs.size());
    if (best == 0 || corrected < best) best = corrected;
  }
  ASSERT_GT(best, 0);
  const double term = reference_noise_mrse(deep, variance, region);
  const double ratio = term / best;
  const double predicted =
      result.reference.sizing->predicted_share / (1 - result.reference.sizing->predicted_share);
  std::printf("sized reference: %u spp (asked %.0f), predicted ratio %.4f, measured %.4f in %s\n",
              result.reference.spp, result.reference.sizing->required_spp, predicted, ratio,
              region_name.c_str());
  EXPECT_GT(ratio, predicted / 3);
  EXPECT_LT(ratio, predicted * 3);
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
