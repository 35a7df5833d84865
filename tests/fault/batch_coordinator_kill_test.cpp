// Fault: the coordinator SIGKILLed at random moments while a batch (penumbra.v1.Batches) runs,
// restarted each time on its data directory and port. The batch resumes and ends DONE; its
// reference job and every run are bit-identical to local renders of the same method, spp and
// seed.
// Built only with the farm (PENUMBRA_FARM=ON); otherwise the program reports a skipped test.
#if __has_include("penumbra/v1/farm.pb.h")
#include <gtest/gtest.h>

#include <random>

#include "fault_support.h"
#include "proto/support/batch_client.h"

namespace penumbra::farm::fault {
namespace {

[[maybe_unused]] auto* const table = ::testing::AddGlobalTestEnvironment(new FaultTableEnvironment);

TEST(FaultBatchCoordinatorKill, RandomKillsDuringABatchLoseNothing) {
  // Plain processes on loopback: no root needed.
  auto dir = testing::fresh_directory("fault-batch-kill");
  std::string scene = testing::write_scene(dir, 64, 64);
  auto coordinator = std::make_unique<testing::CoordinatorProcess>(dir / "data", 0,
                                                                   std::vector<std::string>{}, 1.0);
  const int port = coordinator->port();
  const std::string address = coordinator->address();
  std::vector<std::unique_ptr<testing::ChildProcess>> workers;
  for (int w = 0; w < 2; ++w)
    workers.push_back(testing::start_worker(address, dir, "w" + std::to_string(w)));

  // spp levels only (no calibration): every run's pass count, and so its image, is fixed.
  const std::string spec = R"({
    "format": "penumbra/batch@1", "name": "fault-batch", "scene": "farm-test.json",
    "methods": ["sa"], "budget": {"spp": [32, 128]},
    "reference": {"method": "sa", "sampler": "stratified", "spp": 256, "seed": 9},
    "seed": 3, "repeats": 2
  })";
  std::string batch_id;
  {
    BatchClient client(address);
    batch_id =
        client
            .submit(make_batch_request_from_text(spec, "fault-batch.json", dir.string(),
                                                 [](const std::string& name) { return name; }))
            .batch_id();
  }
  auto batch_status = [&]() -> std::optional<v1::BatchStatus> {
    try {
      return BatchClient(address).status(batch_id);
    } catch (const FarmCallError&) {
      return std::nullopt;  // restarting
    }
  };

  std::mt19937 random(1907);
  std::uniform_int_distribution<int> uptime_ms(300, 1200);
  int kills = 0;
  auto start = Clock::now();
  while (kills < 5 && seconds_since(start) < 30.0) {
    std::this_thread::sleep_for(std::chrono::milliseconds(uptime_ms(random)));
    auto status = batch_status();
    if (status && is_terminal(status->state())) break;
    coordinator->process().signal(SIGKILL);
    coordinator->process().wait_exit(10s);
    ++kills;
    coordinator.reset();
    coordinator = std::make_unique<testing::CoordinatorProcess>(dir / "data", port,
                                                                std::vector<std::string>{}, 1.0);
    status = batch_status();
    ASSERT_TRUE(status.has_value()) << "the restarted coordinator does not know the batch";
    EXPECT_NE(status->state(), v1::BATCH_STATE_FAILED) << status->error();
  }
  std::printf("%d coordinator kills during the batch in %.1f s\n", kills, seconds_since(start));
  EXPECT_GE(kills, 1) << "the batch ended before the first kill";

  std::optional<v1::BatchStatus> final;
  auto deadline = Clock::now() + 60s;
  while (Clock::now() < deadline) {
    final = batch_status();
    if (final && is_terminal(final->state())) break;
    std::this_thread::sleep_for(50ms);
  }
  ASSERT_TRUE(final.has_value());
  ASSERT_EQ(final->state(), v1::BATCH_STATE_DONE) << final->error();

  std::vector<SubmittedJob> jobs;
  jobs.push_back({final->reference().job_id(), "sa", 256, 9});
  for (const v1::BatchMethodStatus& method : final->methods())
    for (const v1::BatchRun& run : method.runs())
      jobs.push_back({run.job_id(), method.method(), run.spp_planned(), run.seed()});
  EXPECT_EQ(jobs.size(), 5u) << "a reference and 2 spp levels x 2 repeats";
  FaultRow row{"coordinator SIGKILL + restart during a batch", kills};
  check_jobs(address, scene, jobs, row);
  record_fault_row(row);
  EXPECT_EQ(row.lost_jobs, 0);
  EXPECT_EQ(row.mismatched_images, 0);
}

}  // namespace
}  // namespace penumbra::farm::fault
#else
#include <gtest/gtest.h>
TEST(FarmNotBuilt, Skipped) {
  GTEST_SKIP() << "configured with PENUMBRA_FARM=OFF";
}
#endif
