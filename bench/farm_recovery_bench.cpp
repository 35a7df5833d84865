// Time to recover, on real processes on loopback:
//  - CoordinatorRestartToFirstLease: a penumbra-coordinator process running a job with two
//    penumbra-worker processes is SIGKILLed and started again on its data directory and port;
//    time from the restart (spawn) to the first task a worker holds again (ListWorkers shows a
//    lease). Counter listen_s: spawn to listening (store opened, jobs resumed).
//  - WorkerLossToTasksElsewhere: an in-process coordinator (its counters are read directly) with
//    a lease of 1 s; a worker process holding leases is SIGKILLed; time from the kill until its
//    tasks are leased to the surviving worker (manual time). Counter expired_s: kill to the
//    expiry that queues them again (bounded by the lease time plus the expiry period, lease/4).
// The binaries are found next to this one: <build>/bench/.. /server, /worker.
//
//   cmake -S . -B build-faults -G Ninja -DPENUMBRA_FARM=ON -DPENUMBRA_BENCH=ON
//   ninja -C build-faults farm_recovery_bench penumbra-coordinator penumbra-worker
//   build-faults/bench/farm_recovery_bench
//
// Linked with penumbra_farm by server/CMakeLists.txt; without the farm it only says so.
#if __has_include("penumbra/v1/farm.grpc.pb.h")
#include <benchmark/benchmark.h>
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <thread>

#include "farm_bench_support.h"
#include "proto/support/farm_client.h"
#include "proto/support/scene_packing.h"
#include "server/coordinator.h"
#include "server/coordinator_server.h"

extern char** environ;

namespace penumbra::farm {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

// A job that outlasts the benchmark: 16 tiles of 16x16, 4096 blocks of one pass.
v1::JobSpec long_job() {
  return bench::plane_job("bench-recovery", 64, 4096, 16);
}

std::filesystem::path build_dir() {
  return std::filesystem::read_symlink("/proc/self/exe").parent_path().parent_path();
}

// A child process (output to a log file), SIGKILLed when destroyed.
class Process {
 public:
  Process(const std::vector<std::string>& arguments, const std::filesystem::path& log) {
    std::vector<char*> argv;
    for (const std::string& argument : arguments)
      argv.push_back(const_cast<char*>(argument.c_str()));
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
    if (posix_spawn(&pid_, argv[0], &actions, nullptr, argv.data(), environ) != 0)
      throw std::runtime_error("cannot start " + arguments[0]);
    posix_spawn_file_actions_destroy(&actions);
  }
  ~Process() { kill(); }
  void kill() {
    if (pid_ <= 0) return;
    ::kill(pid_, SIGKILL);
    ::waitpid(pid_, nullptr, 0);
    pid_ = -1;
  }

 private:
  pid_t pid_ = -1;
};

std::unique_ptr<Process> start_worker(const std::string& address, const std::filesystem::path& dir,
                                      const std::string& name) {
  return std::make_unique<Process>(
      std::vector<std::string>{(build_dir() / "worker/penumbra-worker").string(), "--coordinator",
                               address, "--threads", "1", "--name", name},
      dir / (name + ".log"));
}

std::unique_ptr<Process> start_coordinator(const std::filesystem::path& dir, int port) {
  auto port_file = dir / "port";
  std::filesystem::remove(port_file);
  auto process = std::make_unique<Process>(
      std::vector<std::string>{(build_dir() / "server/penumbra-coordinator").string(), "--listen",
                               "127.0.0.1:" + std::to_string(port), "--data-dir",
                               (dir / "data").string(), "--port-file", port_file.string(),
                               "--lease-seconds", "1"},
      dir / "coordinator.log");
  auto deadline = Clock::now() + 30s;
  while (!std::filesystem::exists(port_file)) {
    if (Clock::now() > deadline) throw std::runtime_error("the coordinator did not start");
    std::this_thread::sleep_for(1ms);
  }
  return process;
}

int port_of(const std::filesystem::path& dir) {
  int port = 0;
  std::ifstream(dir / "port") >> port;
  return port;
}

uint32_t leases_held(FarmClient& client) {
  uint32_t leased = 0;
  try {
    for (const v1::WorkerInfo& worker : client.workers()) leased += worker.tasks_leased();
  } catch (const FarmCallError&) {
  }
  return leased;
}

void CoordinatorRestartToFirstLease(benchmark::State& state) {
  auto dir = bench::fresh_dir("restart");
  auto coordinator = start_coordinator(dir, 0);
  const int port = port_of(dir);
  const std::string address = "127.0.0.1:" + std::to_string(port);
  auto worker_a = start_worker(address, dir, "a");
  auto worker_b = start_worker(address, dir, "b");
  FarmClient(address).submit(long_job());
  double listen_seconds = 0;
  for (auto _ : state) {
    {
      FarmClient client(address);
      auto deadline = Clock::now() + 30s;
      while (leases_held(client) == 0) {
        if (Clock::now() > deadline) {
          state.SkipWithError("no worker leased a task");
          return;
        }
        std::this_thread::sleep_for(2ms);
      }
    }
    std::this_thread::sleep_for(200ms);
    coordinator->kill();
    auto start = Clock::now();
    coordinator = start_coordinator(dir, port);
    listen_seconds += std::chrono::duration<double>(Clock::now() - start).count();
    FarmClient client(address);
    auto deadline = Clock::now() + 30s;
    while (leases_held(client) == 0) {
      if (Clock::now() > deadline) {
        state.SkipWithError("no task was handed out after the restart");
        return;
      }
      std::this_thread::sleep_for(1ms);
    }
    state.SetIterationTime(std::chrono::duration<double>(Clock::now() - start).count());
  }
  state.counters["listen_s"] = benchmark::Counter(listen_seconds / double(state.iterations()));
  coordinator.reset();
  std::filesystem::remove_all(dir);
}
BENCHMARK(CoordinatorRestartToFirstLease)
    ->Iterations(5)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);

void WorkerLossToTasksElsewhere(benchmark::State& state) {
  auto dir = bench::fresh_dir("worker-loss");
  CoordinatorOptions options;
  options.data_dir = (dir / "data").string();
  options.lease_time = 1000ms;
  Coordinator coordinator(options, parse_wire_package);
  CoordinatorServer server(coordinator, "127.0.0.1:0", size_t(64) << 20);
  const std::string address = "127.0.0.1:" + std::to_string(server.port());
  FarmClient(address).submit(long_job());
  auto survivor = start_worker(address, dir, "survivor");
  double expired_seconds = 0;
  int round = 0;
  for (auto _ : state) {
    std::string name = "victim-" + std::to_string(round++);
    auto victim = start_worker(address, dir, name);
    auto held_by_victim = [&] {
      uint32_t leased = 0;
      for (const v1::WorkerInfo& worker : coordinator.workers())
        if (worker.name() == name) leased += worker.tasks_leased();
      return leased;
    };
    auto deadline = Clock::now() + 30s;
    while (held_by_victim() == 0) {
      if (Clock::now() > deadline) {
        state.SkipWithError("the victim never held a lease");
        return;
      }
      std::this_thread::sleep_for(1ms);
    }
    std::this_thread::sleep_for(100ms);
    while (held_by_victim() == 0) std::this_thread::sleep_for(1ms);
    const uint64_t expired_before = coordinator.counters().leases_expired;
    victim->kill();
    auto start = Clock::now();
    const uint32_t held = held_by_victim();
    // Expired: queued again (at the front of its job's queue, so the next leases take them).
    CoordinatorCounters counters = coordinator.counters();
    deadline = Clock::now() + 10s;
    while (counters.leases_expired < expired_before + held) {
      if (Clock::now() > deadline) {
        state.SkipWithError("the lost worker's leases did not expire");
        return;
      }
      std::this_thread::sleep_for(500us);
      counters = coordinator.counters();
    }
    expired_seconds += std::chrono::duration<double>(Clock::now() - start).count();
    const uint64_t leased_at_expiry = counters.tasks_leased;
    while (coordinator.counters().tasks_leased < leased_at_expiry + held) {
      if (Clock::now() > deadline) {
        state.SkipWithError("the lost worker's tasks were not leased again");
        return;
      }
      std::this_thread::sleep_for(500us);
    }
    state.SetIterationTime(std::chrono::duration<double>(Clock::now() - start).count());
  }
  state.counters["expired_s"] = benchmark::Counter(expired_seconds / double(state.iterations()));
  state.counters["lease_s"] = 1.0;
  survivor.reset();
  server.shutdown();
  std::filesystem::remove_all(dir);
}
BENCHMARK(WorkerLossToTasksElsewhere)
    ->Iterations(5)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace penumbra::farm

BENCHMARK_MAIN();
#else
#include <cstdio>
int main() {
  std::puts("farm_recovery_bench: configured without the farm (PENUMBRA_FARM=OFF)");
  return 0;
}
#endif
