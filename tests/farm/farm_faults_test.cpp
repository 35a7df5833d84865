// Worker faults: a worker killed (SIGKILL) or terminated (SIGTERM, drains) mid-job. The finished
// images stay bit-identical to a local render.
// Built only with the farm (PENUMBRA_FARM=ON); otherwise the program reports a skipped test.
#if __has_include("penumbra/v1/farm.pb.h")
#include <gtest/gtest.h>

#include <cmath>
#include <condition_variable>
#include <cstdio>
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

TEST(FarmFaults, KilledWorkerLeasesExpireAndOthersFinishBitIdentical) {
  auto dir = testing::fresh_directory("killed-worker");
  std::string scene = testing::write_scene(dir, 96, 64);
  CoordinatorProcess coordinator(dir / "data", 0, {}, 0.5);
  auto victim = testing::start_worker(coordinator.address(), dir, "victim");
  auto survivor = testing::start_worker(coordinator.address(), dir, "survivor");
  FarmClient client(coordinator.address());
  std::string job = client.submit(testing::job_spec(scene, "sa", 128, 11, 16, 8)).job_id();
  // Kill the victim while it holds leases, after it has delivered some results.
  auto deadline = std::chrono::steady_clock::now() + 60s;
  while (true) {
    bool holding = false;
    for (const v1::WorkerInfo& worker : client.workers())
      holding |=
          worker.name() == "victim" && worker.tasks_completed() >= 3 && worker.tasks_leased() > 0;
    if (holding) break;
    ASSERT_LT(std::chrono::steady_clock::now(), deadline) << "the victim never held a lease";
    std::this_thread::sleep_for(5ms);
  }
  victim->signal(SIGKILL);
  victim->wait_exit(10s);
  // Under load the victim may have delivered its last leased task just before the kill and
  // not leased the next one yet: then no lease can expire. Ask the coordinator what it held
  // (its leases stay in the table until they expire).
  bool victim_held_leases = false;
  for (const v1::WorkerInfo& worker : client.workers())
    if (worker.name() == "victim") victim_held_leases = worker.tasks_leased() > 0;
  v1::JobStatus status = client.wait(job, 120s);
  ASSERT_EQ(status.state(), v1::JOB_STATE_DONE) << status.error();
  EXPECT_EQ(status.tasks_complete(), 24u * 16u);
  expect_bit_identical(client, job, scene, "sa", 128, 11);
  auto workers = client.workers();
  ASSERT_EQ(workers.size(), 2u);
  EXPECT_EQ(workers[0].tasks_completed() + workers[1].tasks_completed(), 24u * 16u)
      << "a task was counted twice or lost";
  // The victim's leases come back by one of two paths, whichever ends first: the coordinator
  // declares the silent worker dead after its missed heartbeats (and requeues what it held), or
  // a lease runs out on its own.
  auto requeued = [](const std::string& log) {
    return log.find("lease of worker w") != std::string::npos ||
           (log.find("silent for") != std::string::npos &&
            log.find(": dead;") != std::string::npos);
  };
  std::string text;
  for (int attempt = 0; attempt < 50; ++attempt) {  // the log is flushed per line; allow 5 s
    std::ifstream log(dir / "data" / "coordinator.log");
    text.assign(std::istreambuf_iterator<char>(log), std::istreambuf_iterator<char>());
    if (requeued(text)) break;
    std::this_thread::sleep_for(100ms);
  }
  if (victim_held_leases || requeued(text))
    EXPECT_TRUE(requeued(text)) << "the victim's leases were neither expired nor released";
  else
    std::printf("note: the victim held no lease when it was killed; no expiry to check\n");
}

// With the default lease (30 s) and heartbeat (1 s), a SIGKILLed worker's tasks go to the other
// worker at its first missed heartbeat: after 1.5 s of silence (the coordinator looks every
// 0.25 s), not when the leases would expire, and not after two missed heartbeats (2.5 s).
TEST(FarmFaults, AKilledWorkersTasksMoveAtItsFirstMissedHeartbeat) {
  auto dir = testing::fresh_directory("first-missed-heartbeat");
  std::string scene = testing::write_scene(dir, 64, 48);
  CoordinatorProcess coordinator(dir / "data", 0, {"--heartbeat-seconds", "1"}, 30.0);
  auto victim = testing::start_worker(coordinator.address(), dir, "victim");
  auto survivor = testing::start_worker(coordinator.address(), dir, "survivor");
  FarmClient client(coordinator.address());
  testing::wait_for_workers(client, 2);
  std::string job =
      client.submit(testing::job_spec(scene, "sa", 32, 11, 32, 8)).job_id();  // 16 tasks
  auto victim_info = [&] {
    for (const v1::WorkerInfo& worker : client.workers())
      if (worker.worker_id() == "victim") return worker;
    throw std::runtime_error("the victim is not listed");
  };
  auto deadline = std::chrono::steady_clock::now() + 60s;
  while (true) {
    v1::WorkerInfo info = victim_info();
    if (info.tasks_leased() > 0) break;
    ASSERT_LT(std::chrono::steady_clock::now(), deadline) << "the victim never held a lease";
    std::this_thread::sleep_for(5ms);
  }
  victim->signal(SIGKILL);
  victim->wait_exit(10s);
  const auto killed = std::chrono::steady_clock::now();
  const v1::WorkerInfo at_kill = victim_info();
  const auto last_contact = std::chrono::steady_clock::now() -
                            std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                std::chrono::duration<double>(at_kill.seconds_since_heartbeat()));
  while (true) {
    v1::WorkerInfo info = victim_info();
    if (!info.alive() && info.tasks_leased() == 0) break;
    ASSERT_LT(std::chrono::steady_clock::now() - killed, 10s) << "the victim kept its tasks";
    std::this_thread::sleep_for(10ms);
  }
  const auto moved = std::chrono::steady_clock::now();
  const double silence = std::chrono::duration<double>(moved - last_contact).count();
  const double after_kill = std::chrono::duration<double>(moved - killed).count();
  std::printf(
      "victim: %u task(s) leased at the kill; released %.2f s after its last contact, "
      "%.2f s after the kill\n",
      at_kill.tasks_leased(), silence, after_kill);
  EXPECT_GE(silence, 1.4) << "declared dead before it missed a heartbeat";
  EXPECT_LT(silence, 2.2) << "not at the first missed heartbeat";
  EXPECT_LT(after_kill, 2.2);
  v1::JobStatus status = client.wait(job, 60s);
  ASSERT_EQ(status.state(), v1::JOB_STATE_DONE) << status.error();
  expect_bit_identical(client, job, scene, "sa", 32, 11);
  uint64_t completed = 0;
  for (const v1::WorkerInfo& worker : client.workers()) completed += worker.tasks_completed();
  EXPECT_EQ(completed, 4u * 4u) << "a task was counted twice or lost";
  std::ifstream log(dir / "data" / "coordinator.log");
  std::string text((std::istreambuf_iterator<char>(log)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("worker victim silent for"), std::string::npos) << text;
  EXPECT_EQ(text.find("lease of worker victim expired"), std::string::npos) << text;
}

// A coordinator that heard nobody for a while (stopped, or holding its lock through a slow disk
// write) must not count its own deafness as the workers' silence: paused (SIGSTOP) for 2 s, four
// times its 0.5 s heartbeat, it declares no worker dead when it resumes; the workers' calls that
// waited meanwhile land first.
TEST(FarmFaults, APausedCoordinatorDeclaresNoWorkerDeadWhenItResumes) {
  auto dir = testing::fresh_directory("paused-coordinator");
  CoordinatorProcess coordinator(dir / "data", 0, {"--heartbeat-seconds", "0.5"}, 30.0);
  auto worker = testing::start_worker(coordinator.address(), dir, "steady");
  FarmClient client(coordinator.address());
  testing::wait_for_workers(client, 1);
  std::this_thread::sleep_for(600ms);  // a heartbeat or two
  coordinator.process().signal(SIGSTOP);
  std::this_thread::sleep_for(2s);
  coordinator.process().signal(SIGCONT);
  std::this_thread::sleep_for(1s);  // several passes of the coordinator's dead-worker check
  const std::vector<v1::WorkerInfo> workers = client.workers();
  ASSERT_EQ(workers.size(), 1u);
  EXPECT_TRUE(workers[0].alive());
  std::ifstream log(dir / "data" / "coordinator.log");
  std::string text((std::istreambuf_iterator<char>(log)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text.find("worker steady silent for"), std::string::npos) << text;
}

TEST(FarmFaults, TerminatedWorkerDrainsAndExitsCleanly) {
  auto dir = testing::fresh_directory("drain");
  std::string scene = testing::write_scene(dir, 96, 64);
  CoordinatorProcess coordinator(dir / "data");
  auto drained = testing::start_worker(coordinator.address(), dir, "drained");
  auto other = testing::start_worker(coordinator.address(), dir, "other");
  FarmClient client(coordinator.address());
  std::string job = client.submit(testing::job_spec(scene, "sa", 64, 5, 16, 8)).job_id();
  // Terminate it once it is running and holds leases.
  auto deadline = std::chrono::steady_clock::now() + 60s;
  while (true) {
    bool holding = false;
    for (const v1::WorkerInfo& worker : client.workers())
      holding |=
          worker.name() == "drained" && worker.tasks_completed() >= 2 && worker.tasks_leased() > 0;
    if (holding) break;
    ASSERT_LT(std::chrono::steady_clock::now(), deadline) << "the worker never held a lease";
    std::this_thread::sleep_for(5ms);
  }
  drained->signal(SIGTERM);
  EXPECT_EQ(drained->wait_exit(30s), 0);
  v1::JobStatus status = client.wait(job, 120s);
  ASSERT_EQ(status.state(), v1::JOB_STATE_DONE) << status.error();
  expect_bit_identical(client, job, scene, "sa", 64, 5);
}

}  // namespace
}  // namespace penumbra::farm
#else
#include <gtest/gtest.h>
TEST(FarmNotBuilt, Skipped) {
  GTEST_SKIP() << "configured with PENUMBRA_FARM=OFF";
}
#endif
