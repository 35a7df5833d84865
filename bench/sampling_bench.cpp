// Cost of the sample patterns: time per 2D (and 1D) sample of each pattern at N = 1, 4, 16, 64,
// including the per-stream setup (key hashing, scrambling seeds, cmj shuffles) shared by the N
// samples of a stream. Every iteration generates one stream for a new pixel.
//
//   ninja -C build-sampling sampling_bench && build-sampling/bench/sampling_bench

#include <benchmark/benchmark.h>

#include <vector>

#include "core/sampling/pattern.h"

namespace penumbra {
namespace {

constexpr Pattern kPatterns[] = {
    Pattern::Random, Pattern::Stratified, Pattern::Uniform, Pattern::UniformJitter,
    Pattern::Halton, Pattern::Sobol,      Pattern::Cmj};

void set_per_sample_counter(benchmark::State& state, int64_t n) {
  state.SetItemsProcessed(state.iterations() * n);
  state.counters["per_sample"] =
      benchmark::Counter(static_cast<double>(state.iterations() * n),
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

void BM_Generate2d(benchmark::State& state, Pattern pattern) {
  int64_t n = state.range(0);
  std::vector<Vec2> points(n);
  StreamKey key{1, 0, 0, 3};
  for (auto _ : state) {
    ++key.pixel;
    generate_2d(pattern, key, 1.0, points);
    benchmark::DoNotOptimize(points.data());
    benchmark::ClobberMemory();
  }
  set_per_sample_counter(state, n);
}

void BM_Generate1d(benchmark::State& state, Pattern pattern) {
  int64_t n = state.range(0);
  std::vector<double> values(n);
  StreamKey key{1, 0, 0, 3};
  for (auto _ : state) {
    ++key.pixel;
    generate_1d(pattern, key, values);
    benchmark::DoNotOptimize(values.data());
    benchmark::ClobberMemory();
  }
  set_per_sample_counter(state, n);
}

void BM_RandomUniform(benchmark::State& state) {
  StreamKey key{1, 0, 0, 3};
  uint32_t sample = 0;
  for (auto _ : state) benchmark::DoNotOptimize(random_uniform(key, ++sample, 0));
  set_per_sample_counter(state, 1);
}

void BM_ConcentricDisk(benchmark::State& state) {
  Vec2 u(0.1234, 0.5678);
  for (auto _ : state) {
    u.x += 0x1p-20;
    if (u.x >= 1.0) u.x -= 1.0;
    benchmark::DoNotOptimize(square_to_disk_concentric(u));
  }
  set_per_sample_counter(state, 1);
}

void register_benchmarks() {
  for (Pattern pattern : kPatterns) {
    std::string name(pattern_name(pattern));
    benchmark::RegisterBenchmark(("generate_2d/" + name).c_str(), BM_Generate2d, pattern)
        ->Arg(1)
        ->Arg(4)
        ->Arg(16)
        ->Arg(64);
  }
  for (Pattern pattern : kPatterns) {
    std::string name(pattern_name(pattern));
    benchmark::RegisterBenchmark(("generate_1d/" + name).c_str(), BM_Generate1d, pattern)
        ->Arg(1)
        ->Arg(16)
        ->Arg(64);
  }
  benchmark::RegisterBenchmark("random_uniform", BM_RandomUniform);
  benchmark::RegisterBenchmark("square_to_disk_concentric", BM_ConcentricDisk);
}

}  // namespace
}  // namespace penumbra

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  penumbra::register_benchmarks();
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
