// Fault: the coordinator SIGKILLed at random moments while jobs run (each kill once the jobs have
// sealed a random number of passes more, with one part-way), restarted each time on its data
// directory and port. Sealed passes are never lost across a restart, no job fails, and every job
// finishes bit-identical to a local render.
// Built only with the farm (PENUMBRA_FARM=ON); otherwise the program reports a skipped test.
#if __has_include("penumbra/v1/farm.pb.h")
#include <gtest/gtest.h>

#include <random>

#include "fault_support.h"

namespace penumbra::farm::fault {
namespace {

[[maybe_unused]] auto* const table = ::testing::AddGlobalTestEnvironment(new FaultTableEnvironment);

TEST(FaultCoordinatorKill, RandomKillsAndRestartsLoseNothing) {
  CoordinatorKillFarm farm("fault-coordinator-kill");
  std::vector<SubmittedJob> jobs;
  auto submit = [&] {
    FarmClient client(farm.address);
    SubmittedJob job{"", "sa", 64, 500 + jobs.size()};
    // 16 tiles x 16 blocks of 4 passes: 256 tasks.
    job.id =
        client.submit(testing::job_spec(farm.scene, job.method, job.spp, job.seed, 16, 4)).job_id();
    jobs.push_back(job);
  };
  for (int j = 0; j < 3; ++j) submit();

  // Each kill comes after 1-32 more passes sealed since the last start, with a job part-way;
  // two jobs or more stay unfinished, so the kills never run out of work (a kill consumes about
  // one poll's worth of tasks beyond its passes: the cap on jobs is far off).
  std::mt19937 random(7411);
  const int wanted_kills = 6;
  const size_t max_jobs = 3 + 2 * wanted_kills;
  auto start = Clock::now();
  int kills = kill_coordinator_on_progress(
      farm.coordinator, wanted_kills, 32, random,
      [&](const FarmProgress& progress) {
        if (progress.unfinished_jobs < 2 && jobs.size() < max_jobs) submit();
      },
      [] { return false; }, [] {}, 180s);
  std::printf("%d coordinator kills in %.1f s, %zu jobs\n", kills, seconds_since(start),
              jobs.size());
  EXPECT_EQ(kills, wanted_kills) << "the kills took longer than 180 s";

  FaultRow row{"coordinator SIGKILL + restart", kills};
  check_jobs(farm.address, farm.scene, jobs, row);
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
