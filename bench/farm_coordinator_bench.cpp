// Coordinator capacity: task completions per second it sustains over gRPC on loopback with many
// fake workers (threads that lease and complete tasks with precomputed tiny tiles, no rendering),
// and its memory per queued task. Goal (PERFORMANCE.md): >= 2,000 completions per second.
//
// Linked with penumbra_farm by server/CMakeLists.txt; without the farm it only says so.
#if __has_include("penumbra/v1/farm.grpc.pb.h")
#include <benchmark/benchmark.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <thread>

#include "farm_bench_support.h"
#include "penumbra/version.h"
#include "proto/support/farm_client.h"
#include "proto/support/scene_packing.h"
#include "server/coordinator.h"
#include "server/coordinator_server.h"

namespace penumbra::farm {
namespace {

v1::JobSpec bench_job(uint32_t spp, uint32_t tile_size) {
  return bench::plane_job("bench-plane", 128, spp, tile_size);
}

long resident_kib() {
  std::ifstream status("/proc/self/status");
  std::string key;
  while (status >> key) {
    long value;
    if (key == "VmRSS:" && status >> value) return value;
  }
  return 0;
}

// Completions per second with state(0) fake workers, each holding up to 4 tasks.
void BM_CoordinatorCompletions(benchmark::State& state) {
  const int worker_count = int(state.range(0));
  std::string dir = bench::fresh_dir("coordinator").string();
  CoordinatorOptions options;
  options.data_dir = dir;
  Coordinator coordinator(options, parse_wire_package);
  CoordinatorServer server(coordinator, "127.0.0.1:0", 64 << 20);
  std::string address = "127.0.0.1:" + std::to_string(server.port());
  FarmClient client(address);
  // 128x128 in 8x8 tiles: 256 tasks per pass.
  const uint32_t spp = 64;
  uint64_t completed_total = 0;
  double seconds_total = 0;
  for (auto _ : state) {
    std::string job = client.submit(bench_job(spp, 8)).job_id();
    std::atomic<uint64_t> completed{0};
    auto start = std::chrono::steady_clock::now();
    std::vector<std::thread> workers;
    for (int w = 0; w < worker_count; ++w) {
      workers.emplace_back([&, w] {
        auto stub = v1::Workers::NewStub(make_farm_channel(address));
        v1::RegisterRequest registration;
        registration.set_name("fake-" + std::to_string(w));
        registration.set_threads(1);
        registration.set_build_flavour(kBuildFlavour);
        registration.set_protocol_version(v1::PROTOCOL_VERSION_CURRENT);
        v1::RegisterResponse registered;
        grpc::ClientContext register_context;
        if (!stub->Register(&register_context, registration, &registered).ok()) return;
        while (true) {
          v1::LeaseTasksRequest lease;
          lease.set_worker_id(registered.worker_id());
          lease.set_max_tasks(4);
          v1::LeaseTasksResponse leased;
          grpc::ClientContext lease_context;
          if (!stub->LeaseTasks(&lease_context, lease, &leased).ok()) return;
          if (leased.tasks_size() == 0) {
            if (client.status(job).state() == v1::JOB_STATE_DONE) return;
            std::this_thread::sleep_for(std::chrono::milliseconds(1));
            continue;
          }
          for (const v1::Task& task : leased.tasks()) {
            TileRect rect{task.tile().x0(), task.tile().y0(), task.tile().x1(), task.tile().y1()};
            TileAccumulator tile(rect);
            for (int64_t i = 0; i < rect.pixel_count(); ++i) tile.add_sample(i, {0.5, 0.25, 1});
            v1::CompleteTaskRequest completion;
            completion.set_worker_id(registered.worker_id());
            completion.set_job_id(task.job_id());
            completion.set_task_index(task.task_index());
            completion.set_attempt_token(task.attempt_token());
            completion.set_tile(tile.serialize());
            completion.set_compute_seconds(0.001);
            v1::CompleteTaskResponse response;
            grpc::ClientContext complete_context;
            if (stub->CompleteTask(&complete_context, completion, &response).ok() &&
                response.accepted())
              ++completed;
          }
        }
      });
    }
    for (auto& worker : workers) worker.join();
    double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    state.SetIterationTime(seconds);
    completed_total += completed;
    seconds_total += seconds;
  }
  state.counters["completions_per_s"] = double(completed_total) / seconds_total;
  std::filesystem::remove_all(dir);
}
BENCHMARK(BM_CoordinatorCompletions)
    ->Arg(4)
    ->Arg(16)
    ->UseManualTime()
    ->Iterations(1)
    ->Unit(benchmark::kSecond);

// Memory per queued task: resident memory growth while a job of 4096 x 256 tasks sits queued.
void BM_CoordinatorMemoryPerQueuedTask(benchmark::State& state) {
  std::string dir = bench::fresh_dir("coordinator").string();
  CoordinatorOptions options;
  options.data_dir = dir;
  options.max_queued_tasks = 10'000'000;
  Coordinator coordinator(options, parse_wire_package);
  double bytes_per_task = 0;
  for (auto _ : state) {
    long before = resident_kib();
    // 128x128 in 4x4 tiles = 1024 tiles x 1024 passes = 1,048,576 queued tasks.
    coordinator.submit(bench_job(1024, 4));
    long after = resident_kib();
    bytes_per_task = double(after - before) * 1024.0 / (1024.0 * 1024.0);
  }
  state.counters["bytes_per_queued_task"] = bytes_per_task;
  std::filesystem::remove_all(dir);
}
BENCHMARK(BM_CoordinatorMemoryPerQueuedTask)->Iterations(1)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace penumbra::farm

BENCHMARK_MAIN();
#else
#include <cstdio>
int main() {
  std::puts("farm_coordinator_bench: built without the farm (PENUMBRA_FARM=OFF)");
  return 0;
}
#endif
