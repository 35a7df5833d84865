// Auto references are rendered once per scene and reference settings, then reused: by a second
// batch, and after a coordinator restart (the cache and the batches are persisted). A batch that
// was running when the coordinator died resumes and finishes after the restart.
#if __has_include("penumbra/v1/farm.pb.h")
#include <gtest/gtest.h>

#include <thread>

#include "tests/batch/batch_test_support.h"
#include "tests/farm/farm_test_support.h"

namespace penumbra::farm {
namespace {

using testing::CoordinatorProcess;

std::string spec_with(const std::string& name, int reference_spp, int spp) {
  return R"({"format": "penumbra/batch@1", "name": ")" + name +
         R"(", "scene": "batch-test.json", "methods": ["sa", "area"],
    "budget": {"spp": [)" +
         std::to_string(spp) + R"(]}, "reference": {"method": "bsdf+sa", "spp": )" +
         std::to_string(reference_spp) + R"(}, "repeats": 1})";
}

TEST(BatchReference, RenderedOncePerSceneAndSpecThenReusedAcrossRestarts) {
  auto dir = testing::fresh_directory("batch-reference");
  testing::write_batch_scene(dir, 32);
  auto coordinator = std::make_unique<CoordinatorProcess>(dir / "data");
  const int port = coordinator->port();
  auto worker = testing::start_worker(coordinator->address(), dir, "w1", 1);

  std::string reference_job;
  {
    BatchClient client(coordinator->address());
    auto first = client.submit(testing::batch_request(dir, spec_with("first", 16, 2)));
    v1::BatchStatus a = testing::run_to_end(client, first.batch_id());
    ASSERT_EQ(a.state(), v1::BATCH_STATE_DONE) << a.error();
    EXPECT_FALSE(a.reference().cached());
    reference_job = a.reference().job_id();
    ASSERT_FALSE(reference_job.empty());

    auto second = client.submit(testing::batch_request(dir, spec_with("second", 16, 4)));
    v1::BatchStatus b = testing::run_to_end(client, second.batch_id());
    ASSERT_EQ(b.state(), v1::BATCH_STATE_DONE) << b.error();
    EXPECT_TRUE(b.reference().cached());
    EXPECT_EQ(b.reference().job_id(), reference_job);

    // Other reference settings: another reference.
    auto third = client.submit(testing::batch_request(dir, spec_with("third", 24, 2)));
    v1::BatchStatus c = testing::run_to_end(client, third.batch_id());
    ASSERT_EQ(c.state(), v1::BATCH_STATE_DONE) << c.error();
    EXPECT_FALSE(c.reference().cached());
    EXPECT_NE(c.reference().job_id(), reference_job);

    // A longer batch, interrupted while it runs.
    auto long_batch = client.submit(testing::batch_request(dir, spec_with("long", 16, 1000)));
    auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (client.status(long_batch.batch_id()).state() == v1::BATCH_STATE_REFERENCE) {
      ASSERT_LT(std::chrono::steady_clock::now(), deadline);
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    EXPECT_EQ(long_batch.batch_id(), "batch-4");
  }
  coordinator.reset();  // SIGKILL
  coordinator = std::make_unique<CoordinatorProcess>(dir / "data", port);
  BatchClient client(coordinator->address());

  // The interrupted batch resumes and finishes; the finished ones are still there.
  v1::BatchStatus resumed = testing::run_to_end(client, "batch-4");
  EXPECT_EQ(resumed.state(), v1::BATCH_STATE_DONE) << resumed.error();
  for (const v1::BatchMethodStatus& method : resumed.methods())
    for (const v1::BatchRun& run : method.runs()) EXPECT_EQ(run.job().passes_complete(), 1000u);
  v1::BatchStatus old = client.status("batch-1");
  EXPECT_EQ(old.state(), v1::BATCH_STATE_DONE);
  EXPECT_EQ(old.name(), "first");
  EXPECT_EQ(client.list().size(), 4u);

  // After the restart the cached reference is reused, and the batch ids go on.
  auto after = client.submit(testing::batch_request(dir, spec_with("after-restart", 16, 2)));
  EXPECT_EQ(after.batch_id(), "batch-5");
  v1::BatchStatus d = testing::run_to_end(client, after.batch_id());
  ASSERT_EQ(d.state(), v1::BATCH_STATE_DONE) << d.error();
  EXPECT_TRUE(d.reference().cached());
  EXPECT_EQ(d.reference().job_id(), reference_job);
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
