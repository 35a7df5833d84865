// Farm overhead: a 512x512, 64 spp cornell-occluders job through an embedded coordinator and one
// worker of T threads, against a local render with T threads (render_local). Same process, same
// run, so machine drift hits both; the counter farm_over_local is the throughput ratio
// (goal: >= 0.95).
//
// Linked with penumbra_farm by server/CMakeLists.txt; without the farm it only says so.
#if __has_include("penumbra/v1/farm.grpc.pb.h")
#include <benchmark/benchmark.h>

#include <thread>

#include "core/render/local_render.h"
#include "proto/support/scene_packing.h"
#include "server/embedded_farm.h"

namespace penumbra::farm {
namespace {

const std::string kScene = std::string(PENUMBRA_SOURCE_DIR) + "/scenes/cornell-occluders.json";
constexpr uint32_t kSpp = 64;

int bench_threads() {
  return int(std::max(1u, std::thread::hardware_concurrency()));
}

double local_seconds = 0, farm_seconds = 0;

void BM_LocalRender(benchmark::State& state) {
  auto scene = std::make_shared<const Scene>(load_scene(kScene));
  RenderOptions options;
  options.method = "sa";
  Renderer renderer(scene, options);
  for (auto _ : state) {
    auto start = std::chrono::steady_clock::now();
    RenderBudget budget;
    budget.spp = kSpp;
    benchmark::DoNotOptimize(render_local(renderer, budget, bench_threads()));
    local_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    state.SetIterationTime(local_seconds);
  }
  state.counters["samples_per_s"] = 512.0 * 512.0 * kSpp / local_seconds;
}
BENCHMARK(BM_LocalRender)->UseManualTime()->Iterations(1)->Unit(benchmark::kSecond);

void BM_FarmRender(benchmark::State& state) {
  EmbeddedFarmOptions options;
  options.workers = 1;
  options.threads_per_worker = bench_threads();
  EmbeddedFarm farm(options);
  v1::JobSpec spec;
  *spec.mutable_scene() = pack_scene_file(kScene);
  spec.set_method("sa");
  spec.set_sampler("stratified");
  spec.set_spp(kSpp);
  for (auto _ : state) {
    auto start = std::chrono::steady_clock::now();
    benchmark::DoNotOptimize(farm.run(spec));
    farm_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    state.SetIterationTime(farm_seconds);
  }
  state.counters["samples_per_s"] = 512.0 * 512.0 * kSpp / farm_seconds;
  if (local_seconds > 0) state.counters["farm_over_local"] = local_seconds / farm_seconds;
}
BENCHMARK(BM_FarmRender)->UseManualTime()->Iterations(1)->Unit(benchmark::kSecond);

}  // namespace
}  // namespace penumbra::farm

BENCHMARK_MAIN();
#else
#include <cstdio>
int main() {
  std::puts("farm_throughput_bench: built without the farm (PENUMBRA_FARM=OFF)");
  return 0;
}
#endif
