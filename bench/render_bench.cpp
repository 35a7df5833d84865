// Throughput of the point-sampling core on cornell-occluders, one thread:
//   ShadowRay        raw Embree shadow rays (our physical limit)
//   DirectSample/M   one whole direct-light sample of method M at a shading point (strategy
//                    sample, shading, pdfs, MIS and the shadow ray), as a ratio to ShadowRay
//   Render512x16     the whole 512x512, 16 spp render with `sa` (seconds; peak RSS)
// Run: build/release/bench/render_bench --benchmark_min_time=1
#include <benchmark/benchmark.h>
#include <sys/resource.h>
#include <tbb/global_control.h>

#include <memory>
#include <random>

#include "core/lights/light_geometry.h"
#include "core/render/camera.h"
#include "core/render/local_render.h"
#include "core/render/shading.h"
#include "core/scene/scene.h"

namespace penumbra {
namespace {

std::shared_ptr<const Scene> bench_scene() {
  static auto scene = std::make_shared<const Scene>(
      load_scene(std::string(PENUMBRA_SOURCE_DIR) + "/scenes/cornell-occluders.json"));
  return scene;
}

// Shading points seen through the pixel centres of a 64x64 grid, and light points for them.
struct Workload {
  std::vector<ShadingPoint> points;
  std::vector<Vec3> light_points;
};

const Workload& workload(const SceneShading& shading) {
  static Workload w = [&] {
    Workload w;
    const Scene& scene = shading.scene();
    CameraRays camera(scene.camera);
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> u(0, 1);
    for (int y = 0; y < 64; ++y)
      for (int x = 0; x < 64; ++x) {
        auto hit = shading.first_hit(camera.origin(),
                                     camera.direction((x + 0.5) * scene.camera.width / 64.0,
                                                      (y + 0.5) * scene.camera.height / 64.0));
        if (!hit.shading_point) continue;
        w.points.push_back(*hit.shading_point);
        w.light_points.push_back(light_point_uniform(scene.lights[0], {u(rng), u(rng)}));
      }
    return w;
  }();
  return w;
}

void ShadowRay(benchmark::State& state) {
  SceneShading shading(bench_scene(), parse_method("sa"));
  const Workload& w = workload(shading);
  size_t i = 0, hits = 0;
  for (auto _ : state) {
    hits += shading.occluded(w.points[i].position, w.points[i].normal, w.light_points[i]);
    if (++i == w.points.size()) i = 0;
  }
  benchmark::DoNotOptimize(hits);
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(ShadowRay);

void DirectSample(benchmark::State& state, const char* method) {
  SceneShading shading(bench_scene(), parse_method(method));
  const Workload& w = workload(shading);
  size_t i = 0;
  uint32_t pass = 0;
  Rgb sum;
  for (auto _ : state) {
    StreamKey key{7, i, pass, 0};
    sum += shading.direct_lighting().estimate(w.points[i], shading, Pattern::Random, key);
    if (++i == w.points.size()) i = 0, ++pass;
  }
  benchmark::DoNotOptimize(sum);
  state.SetItemsProcessed(state.iterations() *
                          shading.direct_lighting().method().total_samples());
}
BENCHMARK_CAPTURE(DirectSample, sa, "sa");
BENCHMARK_CAPTURE(DirectSample, area, "area");
BENCHMARK_CAPTURE(DirectSample, bsdf, "bsdf");
BENCHMARK_CAPTURE(DirectSample, bsdf_sa_balance, "bsdf+sa/balance");

void Render512x16(benchmark::State& state) {
  tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  Renderer renderer(bench_scene(), RenderOptions{"sa", Pattern::Stratified, 0});
  for (auto _ : state) {
    RenderBudget budget;
    budget.spp = 16;
    LocalRenderResult result = render_local(renderer, budget, 1);
    benchmark::DoNotOptimize(result.film.color.rgb.data());
  }
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  state.counters["peak_rss_MiB"] = usage.ru_maxrss / 1024.0;
}
BENCHMARK(Render512x16)->Unit(benchmark::kSecond)->Iterations(1);

}  // namespace
}  // namespace penumbra

BENCHMARK_MAIN();
