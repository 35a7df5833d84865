// Samples per second per thread of the polygon samplers on 3-, 4- and 5-gons, central and
// decentral (cf. Peters 2021, Table 1). Two columns as in the paper: "per light" prepares the
// polygon for every sample (one sample per shading point and light), "per sample" prepares once
// and draws many samples. The goal (PERFORMANCE.md) is psa within 4x of sa; compare ratios from
// one run.
//
// Two levels:
// - samplers of directions (sa_*: Peters' solid angle sampling, core/math/solid_angle_polygon.h;
//   sa_arvo_*: Arvo's original, core/math/arvo_solid_angle.h; psa_*), as in the paper;
// - the point strategies the estimator runs (strategy_<name>_*: area, sa, psa, ltc on a ggx
//   material), which add the plane hit and the area-measure pdf: what a method pays.
//
//   polygon_bench --benchmark_filter=per_ --benchmark_repetitions=5
//                 --benchmark_report_aggregates_only=true

#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <vector>

#include "core/math/arvo_solid_angle.h"
#include "core/math/projected_solid_angle.h"
#include "core/math/solid_angle_polygon.h"
#include "core/math/vec.h"
#include "core/strategies/area_strategy.h"
#include "core/strategies/ltc_strategy.h"
#include "core/strategies/psa_strategy.h"
#include "core/strategies/solid_angle_strategy.h"

namespace penumbra {
namespace {

constexpr int kConfigurations = 64;
constexpr int kRandomPairs = 4096;

// Regular n-gons facing a shading point at the origin with normal +z (local frame), slightly
// jittered per configuration. Central: the polygon covers the zenith; decentral: it lies off to
// the side, above the horizon.
std::vector<std::vector<Vec3>> polygons(int n, bool central) {
  std::mt19937_64 rng(n * 2 + central);
  std::uniform_real_distribution<double> jitter(-0.1, 0.1);
  std::vector<std::vector<Vec3>> result;
  for (int k = 0; k < kConfigurations; ++k) {
    Vec3 center =
        central ? Vec3{jitter(rng), jitter(rng), 1.0} : Vec3{1.5 + jitter(rng), jitter(rng), 1.0};
    double phase = jitter(rng);
    std::vector<Vec3> polygon;
    for (int i = 0; i < n; ++i) {
      // Clockwise about +z seen from above, i.e. counter-clockwise seen from the point below.
      double angle = phase - 2.0 * kPi * i / n;
      polygon.push_back(center + Vec3{0.5 * std::cos(angle), 0.5 * std::sin(angle), 0.0});
    }
    result.push_back(polygon);
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

template <typename Sampler>
void per_light(benchmark::State& state, bool central) {
  auto shapes = polygons(int(state.range(0)), central);
  auto u = random_pairs();
  size_t i = 0;
  for (auto _ : state) {
    Sampler sampler(shapes[i % kConfigurations]);
    benchmark::DoNotOptimize(sampler.sample(u[i % kRandomPairs]));
    ++i;
  }
  state.SetItemsProcessed(state.iterations());
}

template <typename Sampler>
void per_sample(benchmark::State& state, bool central) {
  auto shapes = polygons(int(state.range(0)), central);
  auto u = random_pairs();
  std::vector<Sampler> samplers;
  for (const auto& shape : shapes) samplers.emplace_back(shape);
  size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(samplers[(i / 128) % kConfigurations].sample(u[i % kRandomPairs]));
    ++i;
  }
  state.SetItemsProcessed(state.iterations());
}

void sa_per_light(benchmark::State& s) {
  per_light<SolidAnglePolygonSampler>(s, true);
}
void sa_per_sample(benchmark::State& s) {
  per_sample<SolidAnglePolygonSampler>(s, true);
}
void sa_arvo_per_light(benchmark::State& s) {
  per_light<ArvoPolygonSampler>(s, true);
}
void sa_arvo_per_sample(benchmark::State& s) {
  per_sample<ArvoPolygonSampler>(s, true);
}
void psa_central_per_light(benchmark::State& s) {
  per_light<ProjectedSolidAngleSampler>(s, true);
}
void psa_central_per_sample(benchmark::State& s) {
  per_sample<ProjectedSolidAngleSampler>(s, true);
}
void psa_decentral_per_light(benchmark::State& s) {
  per_light<ProjectedSolidAngleSampler>(s, false);
}
void psa_decentral_per_sample(benchmark::State& s) {
  per_sample<ProjectedSolidAngleSampler>(s, false);
}

BENCHMARK(sa_per_light)->DenseRange(3, 5);
BENCHMARK(sa_arvo_per_light)->DenseRange(3, 5);
BENCHMARK(psa_central_per_light)->DenseRange(3, 5);
BENCHMARK(psa_decentral_per_light)->DenseRange(3, 5);
BENCHMARK(sa_per_sample)->DenseRange(3, 5);
BENCHMARK(sa_arvo_per_sample)->DenseRange(3, 5);
BENCHMARK(psa_central_per_sample)->DenseRange(3, 5);
BENCHMARK(psa_decentral_per_sample)->DenseRange(3, 5);

// The point strategies on the same polygons as polygon lights (emitting towards the shading
// point at the origin, normal +z; a ggx material for ltc, viewed obliquely).
struct StrategySetup {
  Material material;
  std::vector<Light> lights;
  ShadingPoint sp;
  StrategySetup(int n, bool central) {
    material.type = MaterialType::Ggx;
    material.diffuse = {0.2, 0.2, 0.2};
    material.specular = {0.8, 0.8, 0.8};
    material.roughness = 0.2;
    sp = ShadingPoint{{0, 0, 0}, {0, 0, 1}, normalize(Vec3{-0.6, 0.1, 1}), &material};
    for (const auto& polygon : polygons(n, central)) {
      Light light;
      light.type = LightType::Polygon;
      light.vertices = polygon;
      Vec3 c = cross(polygon[1] - polygon[0], polygon[2] - polygon[0]);
      light.normal = normalize(c);
      double area = 0;
      for (size_t i = 1; i + 1 < polygon.size(); ++i)
        area += 0.5 * length(cross(polygon[i] - polygon[0], polygon[i + 1] - polygon[0]));
      light.area = area;
      Vec3 centroid;
      for (const Vec3& v : polygon) centroid += v / double(polygon.size());
      light.centroid = centroid;
      lights.push_back(light);
    }
  }
};

template <typename Strategy>
void strategy_per_light(benchmark::State& state, bool central) {
  StrategySetup setup(int(state.range(0)), central);
  auto u = random_pairs();
  size_t i = 0;
  for (auto _ : state) {
    Strategy strategy(setup.sp, setup.lights[i % kConfigurations]);
    benchmark::DoNotOptimize(strategy.sample(u[i % kRandomPairs]));
    ++i;
  }
  state.SetItemsProcessed(state.iterations());
}

template <typename Strategy>
void strategy_per_sample(benchmark::State& state, bool central) {
  StrategySetup setup(int(state.range(0)), central);
  auto u = random_pairs();
  std::vector<Strategy> strategies;
  for (const Light& light : setup.lights) strategies.emplace_back(setup.sp, light);
  size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(strategies[(i / 128) % kConfigurations].sample(u[i % kRandomPairs]));
    ++i;
  }
  state.SetItemsProcessed(state.iterations());
}

#define PENUMBRA_STRATEGY_BENCH(name, Strategy, central)    \
  void strategy_##name##_per_light(benchmark::State& s) {   \
    strategy_per_light<Strategy>(s, central);               \
  }                                                         \
  void strategy_##name##_per_sample(benchmark::State& s) {  \
    strategy_per_sample<Strategy>(s, central);              \
  }                                                         \
  BENCHMARK(strategy_##name##_per_light)->DenseRange(3, 5); \
  BENCHMARK(strategy_##name##_per_sample)->DenseRange(3, 5);

PENUMBRA_STRATEGY_BENCH(area, AreaStrategy, true)
PENUMBRA_STRATEGY_BENCH(sa, SolidAngleStrategy, true)
PENUMBRA_STRATEGY_BENCH(psa_central, ProjectedSolidAngleStrategy, true)
PENUMBRA_STRATEGY_BENCH(psa_decentral, ProjectedSolidAngleStrategy, false)
PENUMBRA_STRATEGY_BENCH(ltc, LtcStrategy, true)

// The backward-error statistic of METHODS.md on the full 10^6 random configurations (the unit
// test runs 2*10^5 unless PENUMBRA_FULL_TESTS=1); reported as counters, timed for information.
void psa_backward_error_1e6(benchmark::State& state) {
  for (auto _ : state) {
    std::mt19937_64 rng(2021);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    auto unit = [&] {
      double z = 2 * uniform(rng) - 1, phi = 2 * kPi * uniform(rng);
      double r = std::sqrt(std::max(0.0, 1 - z * z));
      return Vec3{r * std::cos(phi), r * std::sin(phi), z};
    };
    double max_error = 0;
    int over = 0, rounding_limited = 0, count = 0;
    while (count < 1'000'000) {
      int n = 3 + int(uniform(rng) * 6);
      Vec3 direction = unit();
      if (uniform(rng) < 1.0 / 3.0) direction = normalize(Vec3{direction.x, direction.y, 3.0});
      double distance = std::exp(std::log(0.01) + uniform(rng) * std::log(1e4));
      double radius = distance * std::exp(std::log(0.01) + uniform(rng) * std::log(300.0));
      double aspect = 0.1 + 0.9 * uniform(rng);
      Frame frame = Frame::from_normal(unit());
      std::vector<double> angles(n);
      for (double& a : angles) a = 2 * kPi * uniform(rng);
      std::sort(angles.begin(), angles.end());
      std::vector<Vec3> polygon;
      for (double a : angles)
        polygon.push_back(direction * distance + frame.s * (radius * std::cos(a)) +
                          frame.t * (radius * aspect * std::sin(a)));
      ProjectedSolidAngleSampler sampler(polygon);
      if (sampler.projected_solid_angle() == 0) continue;
      Vec2 u{uniform(rng), uniform(rng)};
      std::optional<Vec3> d = sampler.sample(u);
      ++count;
      if (!d) {
        ++over;
        continue;
      }
      if (sampler.area_cancellation(u.x) > 1e10) {
        ++rounding_limited;
        continue;
      }
      double error = sampler.backward_error(u, *d);
      max_error = std::max(max_error, error);
      over += error >= 1e-5;
    }
    state.counters["max_backward_error"] = max_error;
    state.counters["over_1e-5"] = over;
    state.counters["rounding_limited"] = rounding_limited;
  }
}
BENCHMARK(psa_backward_error_1e6)->Iterations(1)->Unit(benchmark::kSecond);

}  // namespace
}  // namespace penumbra

BENCHMARK_MAIN();
