// Fault: a worker in its own network namespace is cut off from the coordinator (the host side of
// its veth down) for longer than its lease, twice, then healed. Its leases expire and other
// workers take its tasks; the results it rendered meanwhile arrive late and are dropped, never
// counted twice (the coordinator's counters: late_results > 0, tasks_completed == tasks); every
// job finishes bit-identical to a local render.
// Built only with the farm (PENUMBRA_FARM=ON); otherwise the program reports a skipped test.
#if __has_include("penumbra/v1/farm.pb.h")
#include <gtest/gtest.h>

#include "fault_support.h"

namespace penumbra::farm::fault {
namespace {

[[maybe_unused]] auto* const table = ::testing::AddGlobalTestEnvironment(new FaultTableEnvironment);

TEST(FaultPartition, LateResultsOfACutOffWorkerAreDroppedNotDoubleCounted) {
  PENUMBRA_REQUIRE_ROOT_NETWORK();
  auto dir = testing::fresh_directory("fault-partition");
  std::string scene = testing::write_scene(dir, 64, 64);
  const auto lease = 1000ms;
  const auto partition = 2500ms;
  InProcessCoordinator coordinator(dir / "data", lease, "0.0.0.0:0");
  NetNamespace ns;
  auto victim =
      ns.start_worker(ns.host_ip() + ":" + std::to_string(coordinator.port()), dir, "victim");
  auto helper = testing::start_worker(coordinator.address(), dir, "helper");

  FarmClient client(coordinator.address());
  std::vector<SubmittedJob> jobs;
  auto submit = [&] {
    // 16 tiles of 16x16, blocks of 16 passes: tasks long enough to be caught mid-render.
    SubmittedJob job{"", "sa", 256, 77 + jobs.size()};
    job.id =
        client.submit(testing::job_spec(scene, job.method, job.spp, job.seed, 16, 16)).job_id();
    jobs.push_back(job);
  };
  submit();

  const int rounds = 2;
  int partitions = 0;
  Coordinator& core = coordinator.coordinator();
  auto deadline = Clock::now() + 120s;
  while (partitions < rounds) {
    ASSERT_LT(Clock::now(), deadline) << "the victim was not cut off while holding a lease";
    if (core.counters().queued_tasks < 32) submit();
    // Cut the victim off while it holds leases. Work stays queued meanwhile: a healed victim may
    // take seconds to come back (TCP retransmits after the outage), and the helper alone would
    // finish the jobs before it does.
    while (coordinator.leased_by("victim") == 0) {
      ASSERT_LT(Clock::now(), deadline) << "the victim never held a lease";
      if (core.counters().queued_tasks < 32) submit();
      std::this_thread::sleep_for(2ms);
    }
    uint64_t expired_before = core.counters().leases_expired;
    ns.set_link(false);
    uint64_t held = coordinator.leased_by("victim");
    if (held == 0) {
      // Its lease ended between the look and the cut: no partition of a worker at work, again.
      ns.set_link(true);
      continue;
    }
    ++partitions;
    std::this_thread::sleep_for(partition);
    uint64_t expired = core.counters().leases_expired - expired_before;
    std::printf("partition %d: victim held %llu leases at the cut; %llu leases expired in %.1f s\n",
                partitions, (unsigned long long)held, (unsigned long long)expired,
                std::chrono::duration<double>(partition).count());
    EXPECT_GE(expired, held) << "the cut-off worker's leases did not expire";
    EXPECT_EQ(coordinator.leased_by("victim"), 0u);
    ns.set_link(true);
    // Back on the network: it delivers what it rendered meanwhile (dropped as late).
    auto heal_deadline = Clock::now() + 20s;
    while (core.counters().late_results == 0 && Clock::now() < heal_deadline)
      std::this_thread::sleep_for(10ms);
  }

  FaultRow row{"worker partitioned > lease (veth down)", partitions};
  check_jobs(coordinator.address(), scene, jobs, row);
  uint64_t tasks_total = 0;
  for (const SubmittedJob& job : jobs) tasks_total += client.status(job.id).tasks_total();
  CoordinatorCounters counters = core.counters();
  std::printf("tasks %llu: completed %llu, leases expired %llu, late results dropped %llu\n",
              (unsigned long long)tasks_total, (unsigned long long)counters.tasks_completed,
              (unsigned long long)counters.leases_expired,
              (unsigned long long)counters.late_results);
  EXPECT_GT(counters.late_results, 0u) << "no late result arrived";
  EXPECT_EQ(counters.tasks_completed, tasks_total) << "a task was counted twice or never";
  EXPECT_EQ(coordinator.completed_by_all(), tasks_total);
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
