// The farm end to end: coordinator and worker processes on loopback, images bit-identical to
// a local render, concurrent jobs, error curves against a reference job.
// Built only with the farm (PENUMBRA_FARM=ON); otherwise the program reports a skipped test.
#if __has_include("penumbra/v1/farm.pb.h")
#include <gtest/gtest.h>

#include <cmath>
#include <condition_variable>
#include <mutex>

#include "core/image/metrics.h"
#include "farm_test_support.h"
#include "penumbra/version.h"

namespace penumbra::farm {
namespace {

using namespace std::chrono_literals;
using testing::CoordinatorProcess;
using testing::expect_bit_identical;

TEST(FarmIntegration, TwoWorkersRenderBitIdenticalToLocal) {
  auto dir = testing::fresh_directory("two-workers");
  std::string scene = testing::write_scene(dir, 64, 48);
  CoordinatorProcess coordinator(dir / "data");
  auto worker_a = testing::start_worker(coordinator.address(), dir, "a");
  auto worker_b = testing::start_worker(coordinator.address(), dir, "b");
  FarmClient client(coordinator.address());
  // Both at the coordinator before the job: 48 short tasks can end before a slow worker joins.
  testing::wait_for_workers(client, 2);
  auto submitted = client.submit(testing::job_spec(scene, "sa", 16, 7));
  std::vector<v1::JobStatus> events;
  v1::JobStatus final_status = client.watch(
      submitted.job_id(), [&](const v1::JobStatus& s) { events.push_back(s); }, 60s);
  ASSERT_EQ(final_status.state(), v1::JOB_STATE_DONE) << final_status.error();
  EXPECT_EQ(final_status.passes_complete(), 16u);
  EXPECT_EQ(final_status.tiles_total(), 12u);  // 64x48 in 16x16 tiles
  EXPECT_EQ(final_status.tiles_complete(), 12u);
  EXPECT_EQ(final_status.tasks_complete(), 48u);  // 12 tiles x 4 blocks of 4 passes
  EXPECT_GT(final_status.compute_seconds(), 0.0);
  ASSERT_GE(events.size(), 2u);
  for (size_t i = 1; i < events.size(); ++i)
    EXPECT_GE(events[i].tasks_complete(), events[i - 1].tasks_complete());
  expect_bit_identical(client, submitted.job_id(), scene, "sa", 16, 7);
  auto workers = client.workers();
  ASSERT_EQ(workers.size(), 2u);
  uint64_t completed = 0;
  for (const auto& worker : workers) completed += worker.tasks_completed();
  EXPECT_EQ(completed, 48u);
}

TEST(FarmIntegration, ConcurrentJobsAllCompleteBitIdentical) {
  auto dir = testing::fresh_directory("concurrent");
  std::string scene = testing::write_scene(dir, 64, 48);
  CoordinatorProcess coordinator(dir / "data");
  auto worker_a = testing::start_worker(coordinator.address(), dir, "a");
  auto worker_b = testing::start_worker(coordinator.address(), dir, "b");
  struct Submitted {
    std::string job, method;
    uint32_t spp;
    uint64_t seed;
  };
  std::vector<Submitted> jobs = {{"", "sa", 16, 1}, {"", "area", 12, 2}, {"", "sa", 20, 3}};
  FarmClient client(coordinator.address());
  for (Submitted& job : jobs)
    job.job =
        client.submit(testing::job_spec(scene, job.method, job.spp, job.seed, 16, 3)).job_id();
  for (const Submitted& job : jobs) {
    v1::JobStatus status = client.wait(job.job, 60s);
    ASSERT_EQ(status.state(), v1::JOB_STATE_DONE) << job.job << ": " << status.error();
    expect_bit_identical(client, job.job, scene, job.method, job.spp, job.seed);
  }
  EXPECT_EQ(client.list().size(), 3u);
}

TEST(FarmIntegration, ReferenceJobGivesErrorCurveAndRegionErrors) {
  auto dir = testing::fresh_directory("reference");
  std::string scene = testing::write_scene(dir, 64, 48);
  CoordinatorProcess coordinator(dir / "data");
  auto worker = testing::start_worker(coordinator.address(), dir, "w", 2);
  FarmClient client(coordinator.address());
  std::string reference = client.submit(testing::job_spec(scene, "sa", 64, 100)).job_id();
  ASSERT_EQ(client.wait(reference, 60s).state(), v1::JOB_STATE_DONE);
  v1::JobSpec spec = testing::job_spec(scene, "sa", 16, 1);
  spec.set_reference_job(reference);
  std::string job = client.submit(spec).job_id();
  ASSERT_EQ(client.wait(job, 60s).state(), v1::JOB_STATE_DONE);
  v1::JobStatus status = client.status(job);
  ASSERT_EQ(status.curve_size(), 4);  // one point per sealed block of 4 passes
  for (int i = 0; i < status.curve_size(); ++i) {
    EXPECT_EQ(status.curve(i).passes(), uint32_t(4 * (i + 1)));
    EXPECT_TRUE(std::isfinite(status.curve(i).mrse()));
    EXPECT_GT(status.curve(i).mrse(), 0.0);
  }
  EXPECT_LT(status.curve(3).mrse(), status.curve(0).mrse()) << "error should fall with passes";
  ASSERT_EQ(status.errors_size(), 2);  // "image" and the scene's one region
  // The final MRSE equals core's metric on the two images.
  Image test = decode_exr(client.fetch(job));
  Image ref = decode_exr(client.fetch(reference));
  for (const auto& error : status.errors())
    if (error.region() == "image") {
      EXPECT_DOUBLE_EQ(error.mrse(), mrse(test, ref));
    }
  EXPECT_DOUBLE_EQ(status.mrse(), status.curve(3).mrse());
}

}  // namespace
}  // namespace penumbra::farm
#else
#include <gtest/gtest.h>
TEST(FarmNotBuilt, Skipped) {
  GTEST_SKIP() << "configured with PENUMBRA_FARM=OFF";
}
#endif
