// Fault: the coordinator SIGKILLed at random moments while jobs run, restarted each time on its
// data directory and port. Sealed passes are never lost across a restart, no job fails, and every
// job finishes bit-identical to a local render.
// Built only with the farm (PENUMBRA_FARM=ON); otherwise the program reports a skipped test.
#if __has_include("penumbra/v1/farm.pb.h")
#include <gtest/gtest.h>

#include <random>

#include "fault_support.h"

namespace penumbra::farm::fault {
namespace {

[[maybe_unused]] auto* const table = ::testing::AddGlobalTestEnvironment(new FaultTableEnvironment);

TEST(FaultCoordinatorKill, RandomKillsAndRestartsLoseNothing) {
  // Plain processes on loopback: no root needed.
  auto dir = testing::fresh_directory("fault-coordinator-kill");
  std::string scene = testing::write_scene(dir, 64, 64);
  auto coordinator = std::make_unique<testing::CoordinatorProcess>(dir / "data", 0,
                                                                   std::vector<std::string>{}, 1.0);
  const int port = coordinator->port();
  const std::string address = coordinator->address();
  std::vector<std::unique_ptr<testing::ChildProcess>> workers;
  for (int w = 0; w < 2; ++w)
    workers.push_back(testing::start_worker(address, dir, "w" + std::to_string(w)));

  std::vector<SubmittedJob> jobs;
  auto submit = [&] {
    FarmClient client(address);
    SubmittedJob job{"", "sa", 64, 500 + jobs.size()};
    // 16 tiles x 16 blocks of 4 passes: 256 tasks.
    job.id = client.submit(testing::job_spec(scene, job.method, job.spp, job.seed, 16, 4)).job_id();
    jobs.push_back(job);
  };
  for (int j = 0; j < 3; ++j) submit();

  std::mt19937 random(7411);
  std::uniform_int_distribution<int> uptime_ms(300, 1500);
  const int wanted_kills = 6;
  int kills = 0;
  std::map<std::string, uint32_t> passes_seen;
  auto start = Clock::now();
  while (kills < wanted_kills && seconds_since(start) < 40.0) {
    std::this_thread::sleep_for(std::chrono::milliseconds(uptime_ms(random)));
    {
      FarmClient client(address);
      bool all_done = true;
      for (const SubmittedJob& job : jobs) {
        v1::JobStatus status = client.status(job.id);
        all_done &= status.state() == v1::JOB_STATE_DONE;
        passes_seen[job.id] = status.passes_complete();
      }
      if (all_done) {
        if (jobs.size() >= 8) break;
        submit();
        continue;
      }
    }
    coordinator->process().signal(SIGKILL);
    coordinator->process().wait_exit(10s);
    ++kills;
    coordinator.reset();
    coordinator = std::make_unique<testing::CoordinatorProcess>(dir / "data", port,
                                                                std::vector<std::string>{}, 1.0);
    FarmClient client(address);
    for (const SubmittedJob& job : jobs) {
      v1::JobStatus status = client.status(job.id);
      EXPECT_NE(status.state(), v1::JOB_STATE_FAILED) << job.id << ": " << status.error();
      EXPECT_GE(status.passes_complete(), passes_seen[job.id])
          << job.id << ": sealed passes were lost in the restart";
    }
  }
  std::printf("%d coordinator kills in %.1f s, %zu jobs\n", kills, seconds_since(start),
              jobs.size());
  EXPECT_GE(kills, 3) << "the jobs finished before the coordinator was killed often enough";

  FaultRow row{"coordinator SIGKILL + restart", kills};
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
