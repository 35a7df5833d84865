// Samples per second per thread of LTC sampling (`ltc`, LtcStrategy: a point on the light with
// its area pdf) on 3-, 4- and 5-gons, with psa (ProjectedSolidAngleStrategy) on the same lights
// and shading points for comparison. "per light" prepares the strategy for every sample (table
// lookup, the transformed polygon, psa set-up); "per sample" prepares once per shading point and
// draws many. Also the cost of pdf() (what MIS pays per sample of the other technique).
//
//   ltc_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only=true

#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <vector>

#include "core/strategies/ltc_strategy.h"
#include "core/strategies/psa_strategy.h"

namespace penumbra {
namespace {

constexpr int kConfigurations = 64;
constexpr int kRandomPairs = 4096;

struct Configuration {
  Light light;
  ShadingPoint sp;
};

// Regular n-gons on the ceiling (y = 1, emitting down) above shading points with normal +y,
// slightly jittered, viewed obliquely so that the highlight falls on or near the light; a glossy
// ggx material (roughness 0.3).
const Material& glossy() {
  static const Material material = [] {
    Material m;
    m.type = MaterialType::Ggx;
    m.diffuse = {0.3, 0.3, 0.3};
    m.specular = {0.5, 0.5, 0.5};
    m.roughness = 0.3;
    return m;
  }();
  return material;
}

std::vector<Configuration> configurations(int n) {
  std::mt19937_64 rng(n);
  std::uniform_real_distribution<double> jitter(-0.2, 0.2);
  std::vector<Configuration> result;
  for (int k = 0; k < kConfigurations; ++k) {
    Light light;
    light.type = LightType::Polygon;
    Vec3 center{jitter(rng), 1.0, jitter(rng)};
    double phase = jitter(rng);
    for (int i = 0; i < n; ++i) {
      double angle = phase + 2.0 * kPi * i / n;  // counter-clockwise seen from below
      light.vertices.push_back(center + Vec3{0.4 * std::cos(angle), 0, 0.4 * std::sin(angle)});
    }
    light.normal = {0, -1, 0};  // cross(v1 - v0, v2 - v0) points down: emits towards y < 1
    ShadingPoint sp;
    sp.position = {0.5 + jitter(rng), 0, jitter(rng)};
    sp.normal = {0, 1, 0};
    sp.wo = normalize(Vec3{1.0 + jitter(rng), 1.0, jitter(rng)});
    sp.material = &glossy();
    result.push_back({light, sp});
  }
  return result;
}

std::vector<Vec2> random_pairs() {
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::vector<Vec2> u(kRandomPairs);
  for (Vec2& p : u) p = {uniform(rng), uniform(rng)};
  return u;
}

// Fraction of samples that come back non-empty, as a counter (a sanity check of the set-up).
template <typename Strategy>
double success_rate(const std::vector<Configuration>& shapes, const std::vector<Vec2>& u) {
  int successes = 0, total = 0;
  for (const Configuration& c : shapes) {
    Strategy strategy(c.sp, c.light);
    for (int k = 0; k < 64; ++k, ++total) successes += strategy.sample(u[size_t(k)]).has_value();
  }
  return double(successes) / total;
}

template <typename Strategy>
void per_light(benchmark::State& state) {
  auto shapes = configurations(int(state.range(0)));
  auto u = random_pairs();
  size_t i = 0;
  for (auto _ : state) {
    const Configuration& c = shapes[i % kConfigurations];
    Strategy strategy(c.sp, c.light);
    benchmark::DoNotOptimize(strategy.sample(u[i % kRandomPairs]));
    ++i;
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["success"] = success_rate<Strategy>(shapes, u);
}

template <typename Strategy>
void per_sample(benchmark::State& state) {
  auto shapes = configurations(int(state.range(0)));
  auto u = random_pairs();
  std::vector<Strategy> strategies;
  for (const Configuration& c : shapes) strategies.emplace_back(c.sp, c.light);
  size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(strategies[(i / 128) % kConfigurations].sample(u[i % kRandomPairs]));
    ++i;
  }
  state.SetItemsProcessed(state.iterations());
}

template <typename Strategy>
void pdf_evaluation(benchmark::State& state) {
  auto shapes = configurations(int(state.range(0)));
  auto u = random_pairs();
  std::vector<Strategy> strategies;
  std::vector<Vec3> points;
  for (const Configuration& c : shapes) {
    strategies.emplace_back(c.sp, c.light);
    ProjectedSolidAngleStrategy psa(c.sp, c.light);
    for (int k = 0; k < 64; ++k)
      if (auto p = psa.sample(u[size_t(k)])) points.push_back(p->position);
  }
  if (points.empty()) {
    state.SkipWithError("no light points: the lights face away from the shading points");
    return;
  }
  size_t i = 0;
  for (auto _ : state) {
    size_t configuration = (i / 64) % kConfigurations;
    benchmark::DoNotOptimize(
        strategies[configuration].pdf(points[(configuration * 64 + i % 64) % points.size()]));
    ++i;
  }
  state.SetItemsProcessed(state.iterations());
}

BENCHMARK(per_light<LtcStrategy>)->Name("ltc/per_light")->DenseRange(3, 5);
BENCHMARK(per_light<ProjectedSolidAngleStrategy>)->Name("psa/per_light")->DenseRange(3, 5);
BENCHMARK(per_sample<LtcStrategy>)->Name("ltc/per_sample")->DenseRange(3, 5);
BENCHMARK(per_sample<ProjectedSolidAngleStrategy>)->Name("psa/per_sample")->DenseRange(3, 5);
BENCHMARK(pdf_evaluation<LtcStrategy>)->Name("ltc/pdf")->DenseRange(3, 5);
BENCHMARK(pdf_evaluation<ProjectedSolidAngleStrategy>)->Name("psa/pdf")->DenseRange(3, 5);

}  // namespace
}  // namespace penumbra

BENCHMARK_MAIN();
