// Fault: workers SIGKILLed at random moments while jobs run, each restarted at once (at least 20
// kills, of workers holding leases, in a run). Every job must finish, bit-identical to a local
// render, and no task may be counted twice: the coordinator accepts exactly one result per task.
// Built only with the farm (PENUMBRA_FARM=ON); otherwise the program reports a skipped test.
#if __has_include("penumbra/v1/farm.pb.h")
#include <gtest/gtest.h>

#include <random>

#include "fault_support.h"

namespace penumbra::farm::fault {
namespace {

[[maybe_unused]] auto* const table = ::testing::AddGlobalTestEnvironment(new FaultTableEnvironment);

TEST(FaultWorkerKill, RandomKillsAndRestartsLoseNothing) {
  // Plain processes on loopback: no root needed.
  auto dir = testing::fresh_directory("fault-worker-kill");
  std::string scene = testing::write_scene(dir, 64, 64);
  InProcessCoordinator coordinator(dir / "data", 1000ms);
  const int worker_count = 5;
  std::vector<std::unique_ptr<testing::ChildProcess>> workers;
  for (int w = 0; w < worker_count; ++w)
    workers.push_back(testing::start_worker(coordinator.address(), dir, worker_name(w)));

  const auto start_up = Clock::now();
  FarmClient client(coordinator.address());
  std::vector<SubmittedJob> jobs;
  uint64_t tasks_total = 0;
  auto submit = [&] {
    SubmittedJob job{"", "sa", 64, 1000 + jobs.size()};
    // 16x16 tiles, 4 passes per task: 16 tiles x 16 blocks = 256 short tasks.
    job.id = client.submit(testing::job_spec(scene, job.method, job.spp, job.seed, 16, 4)).job_id();
    jobs.push_back(job);
    tasks_total += 256;
  };
  for (int j = 0; j < 3; ++j) submit();

  // Each kill comes once the farm has completed a random 1-8 more tasks since the last one, and
  // takes a worker holding leases then (none holds one: wait). A kill thus costs a few tasks of
  // work, never a stretch of the clock: the work queued (kept above 64 tasks) outlasts the kills
  // however fast the machine, and a slow machine only takes longer.
  std::mt19937 random(20261123);
  std::uniform_int_distribution<uint64_t> tasks_between(1, 8);
  std::vector<std::string> names;
  for (int w = 0; w < worker_count; ++w) names.push_back(worker_name(w));
  const int wanted_kills = 20;
  const size_t max_jobs = 24;
  int kills = 0;
  // Start once the farm is at work.
  while (coordinator.coordinator().counters().tasks_completed == 0) {
    ASSERT_LT(seconds_since(start_up), 60.0) << "no task was completed";
    std::this_thread::sleep_for(10ms);
  }
  auto start = Clock::now();
  uint64_t completed_at_kill = coordinator.coordinator().counters().tasks_completed;
  uint64_t wanted_tasks = tasks_between(random);
  while (kills < wanted_kills) {
    ASSERT_LT(seconds_since(start), 180.0) << "the kills took too long";
    std::this_thread::sleep_for(2ms);
    CoordinatorCounters counters = coordinator.coordinator().counters();
    // Keep work queued so that the workers stay busy.
    if (counters.queued_tasks < 64 && jobs.size() < max_jobs) submit();
    if (counters.tasks_completed < completed_at_kill + wanted_tasks) continue;
    // The victim: a random worker among those holding leases now.
    std::vector<size_t> holding;
    for (size_t w = 0; w < workers.size(); ++w)
      if (coordinator.leased_by(names[w]) > 0) holding.push_back(w);
    if (holding.empty()) continue;
    size_t w = holding[std::uniform_int_distribution<size_t>(0, holding.size() - 1)(random)];
    workers[w]->signal(SIGKILL);
    workers[w]->wait_exit(10s);
    ++kills;
    names[w] = worker_name(int(w), kills);
    workers[w] = testing::start_worker(coordinator.address(), dir, names[w]);
    completed_at_kill = coordinator.coordinator().counters().tasks_completed;
    wanted_tasks = tasks_between(random);
  }
  std::printf("%d kills in %.1f s, %zu jobs\n", kills, seconds_since(start), jobs.size());

  FaultRow row{"worker SIGKILL + restart", kills};
  check_jobs(coordinator.address(), scene, jobs, row);
  CoordinatorCounters counters = coordinator.coordinator().counters();
  std::printf(
      "tasks leased %llu, completed %llu, leases expired %llu, late results %llu\n",
      (unsigned long long)counters.tasks_leased, (unsigned long long)counters.tasks_completed,
      (unsigned long long)counters.leases_expired, (unsigned long long)counters.late_results);
  EXPECT_EQ(counters.tasks_completed, tasks_total) << "a task was accepted twice or never";
  EXPECT_EQ(coordinator.completed_by_all(), tasks_total);
  EXPECT_GT(counters.leases_expired, 0u) << "no lease of a killed worker expired";
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
