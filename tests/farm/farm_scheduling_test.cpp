// Scheduling through the API: cancel, priorities, seconds budgets that stop at a pass boundary.
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
using testing::wait_until;

TEST(FarmScheduling, CancelEndsTheJobAndFreesWorkers) {
  auto dir = testing::fresh_directory("cancel");
  std::string scene = testing::write_scene(dir, 96, 64);
  CoordinatorProcess coordinator(dir / "data");
  auto worker = testing::start_worker(coordinator.address(), dir, "w");
  FarmClient client(coordinator.address());
  std::string big = client.submit(testing::job_spec(scene, "sa", 4096, 1, 16, 4)).job_id();
  wait_until(client, big, [](const v1::JobStatus& s) { return s.tasks_complete() >= 2; });
  EXPECT_EQ(client.cancel(big), v1::JOB_STATE_CANCELLED);
  EXPECT_EQ(client.status(big).state(), v1::JOB_STATE_CANCELLED);
  try {
    client.fetch(big);
    ADD_FAILURE() << "fetching a cancelled job's result should fail";
  } catch (const FarmCallError& error) {
    EXPECT_EQ(error.code(), grpc::StatusCode::FAILED_PRECONDITION);
  }
  // The worker moves on to the next job.
  std::string small = client.submit(testing::job_spec(scene, "sa", 8, 2)).job_id();
  v1::JobStatus status = client.wait(small, 60s);
  EXPECT_EQ(status.state(), v1::JOB_STATE_DONE) << status.error();
  EXPECT_EQ(client.cancel(small), v1::JOB_STATE_DONE);  // cancelling a finished job is a no-op
}

TEST(FarmScheduling, HigherPriorityJobsAreServedFirst) {
  auto dir = testing::fresh_directory("priority");
  std::string scene = testing::write_scene(dir, 96, 64);
  CoordinatorProcess coordinator(dir / "data");
  FarmClient client(coordinator.address());
  // Submitted before any worker exists: the low-priority job first.
  v1::JobSpec low = testing::job_spec(scene, "sa", 64, 1, 16, 8);
  low.set_priority(0);
  v1::JobSpec high = testing::job_spec(scene, "sa", 16, 2, 16, 8);
  high.set_priority(10);
  std::string low_job = client.submit(low).job_id();
  std::string high_job = client.submit(high).job_id();
  auto worker = testing::start_worker(coordinator.address(), dir, "w");
  v1::JobStatus high_status = client.wait(high_job, 60s);
  ASSERT_EQ(high_status.state(), v1::JOB_STATE_DONE);
  v1::JobStatus low_status = client.status(low_job);
  EXPECT_NE(low_status.state(), v1::JOB_STATE_DONE);
  // A worker holds at most two tasks ahead, so the low job can have started only at the end.
  EXPECT_LE(low_status.tasks_complete(), 2u);
  EXPECT_EQ(client.wait(low_job, 120s).state(), v1::JOB_STATE_DONE);
}

TEST(FarmScheduling, SecondsBudgetStopsAtAPassBoundary) {
  auto dir = testing::fresh_directory("seconds");
  std::string scene = testing::write_scene(dir, 64, 48);
  CoordinatorProcess coordinator(dir / "data");
  auto worker_a = testing::start_worker(coordinator.address(), dir, "a");
  auto worker_b = testing::start_worker(coordinator.address(), dir, "b");
  FarmClient client(coordinator.address());
  v1::JobSpec spec = testing::job_spec(scene, "sa", 1, 9, 16, 8);
  spec.set_compute_seconds(0.2);
  std::string job = client.submit(spec).job_id();
  v1::JobStatus status = client.wait(job, 120s);
  ASSERT_EQ(status.state(), v1::JOB_STATE_DONE) << status.error();
  uint32_t spp = status.passes_complete();
  EXPECT_GT(spp, 0u);
  EXPECT_EQ(spp % 8, 0u) << "stopped inside a pass block";
  EXPECT_EQ(status.passes_planned(), spp);
  EXPECT_GT(status.compute_seconds(), 0.0);
  // Every tile has the same passes: the image is exactly a local render of `spp` passes.
  expect_bit_identical(client, job, scene, "sa", spp, 9);
}

}  // namespace
}  // namespace penumbra::farm
#else
#include <gtest/gtest.h>
TEST(FarmNotBuilt, Skipped) {
  GTEST_SKIP() << "configured with PENUMBRA_FARM=OFF";
}
#endif
