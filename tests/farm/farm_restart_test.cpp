// Coordinator faults and start-up order: a coordinator killed and restarted on its data directory
// keeps its finished tiles; a worker started before its coordinator joins when it comes.
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

TEST(FarmRestart, CoordinatorKilledAndRestartedKeepsFinishedTiles) {
  auto dir = testing::fresh_directory("restart");
  std::string scene = testing::write_scene(dir, 96, 64);
  CoordinatorProcess coordinator(dir / "data");
  auto worker_a = testing::start_worker(coordinator.address(), dir, "a");
  auto worker_b = testing::start_worker(coordinator.address(), dir, "b");
  std::string job;
  uint32_t passes_before = 0;
  {
    FarmClient client(coordinator.address());
    job = client.submit(testing::job_spec(scene, "sa", 128, 3, 16, 8)).job_id();
    passes_before = wait_until(client, job, [](const v1::JobStatus& s) {
                      return s.passes_complete() >= 16;
                    }).passes_complete();
  }
  // SIGKILL, then the same port and data directory: the workers reconnect by themselves.
  coordinator.restart();
  FarmClient client(coordinator.address());
  v1::JobStatus resumed = client.status(job);
  EXPECT_GE(resumed.passes_complete(), passes_before) << "sealed passes were lost";
  EXPECT_NE(resumed.state(), v1::JOB_STATE_FAILED) << resumed.error();
  v1::JobStatus status = client.wait(job, 120s);
  ASSERT_EQ(status.state(), v1::JOB_STATE_DONE) << status.error();
  expect_bit_identical(client, job, scene, "sa", 128, 3);
}

TEST(FarmRestart, WorkerStartedBeforeTheCoordinatorJoinsWhenItComes) {
  auto dir = testing::fresh_directory("early-worker");
  std::string scene = testing::write_scene(dir, 64, 48);
  int port = testing::free_port();
  auto worker = testing::start_worker("127.0.0.1:" + std::to_string(port), dir, "early");
  std::this_thread::sleep_for(1500ms);
  ASSERT_TRUE(worker->running()) << "the worker gave up before the coordinator came";
  CoordinatorProcess coordinator(dir / "data", port);
  FarmClient client(coordinator.address());
  std::string job = client.submit(testing::job_spec(scene, "sa", 8, 6)).job_id();
  v1::JobStatus status = client.wait(job, 60s);
  ASSERT_EQ(status.state(), v1::JOB_STATE_DONE) << status.error();
  expect_bit_identical(client, job, scene, "sa", 8, 6);
}

}  // namespace
}  // namespace penumbra::farm
#else
#include <gtest/gtest.h>
TEST(FarmNotBuilt, Skipped) {
  GTEST_SKIP() << "configured with PENUMBRA_FARM=OFF";
}
#endif
