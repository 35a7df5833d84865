// Throughput of the line methods (Salesin & Jarosz's line-area / line-sa and their MIS and
// smoothing; Billen & Dutré's line-bd16 where the scene's materials allow it), one thread, as
// whole direct-light samples per second at shading points seen through a 64x64 pixel grid, on
// cornell-occluders and monoliths. `sa` is the point-sample baseline: the ratio of its
// items_per_second to a line method's is the cost of a line sample in point samples.
// Run: build/bench/line_methods_bench --benchmark_min_time=1
#include <benchmark/benchmark.h>

#include <map>
#include <memory>
#include <string>

#include "core/render/camera.h"
#include "core/render/shading.h"
#include "core/scene/scene.h"

namespace penumbra {
namespace {

std::shared_ptr<const Scene> bench_scene(const std::string& name) {
  static std::map<std::string, std::shared_ptr<const Scene>> scenes;
  auto& scene = scenes[name];
  if (!scene)
    scene = std::make_shared<const Scene>(
        load_scene(std::string(PENUMBRA_SOURCE_DIR) + "/scenes/" + name + ".json"));
  return scene;
}

std::vector<ShadingPoint> shading_points(const SceneShading& shading) {
  std::vector<ShadingPoint> points;
  const Scene& scene = shading.scene();
  CameraRays camera(scene.camera);
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) {
      auto hit = shading.first_hit(camera.origin(),
                                   camera.direction((x + 0.5) * scene.camera.width / 64.0,
                                                    (y + 0.5) * scene.camera.height / 64.0));
      if (hit.shading_point) points.push_back(*hit.shading_point);
    }
  return points;
}

void DirectSample(benchmark::State& state, const char* scene_name, const char* method) {
  std::unique_ptr<SceneShading> shading;
  try {
    shading = std::make_unique<SceneShading>(bench_scene(scene_name), parse_method(method));
  } catch (const FormatError& e) {
    state.SkipWithError(e.what());
    for (auto _ : state) {
    }
    return;
  }
  std::vector<ShadingPoint> points = shading_points(*shading);
  size_t i = 0;
  uint32_t pass = 0;
  Rgb sum;
  for (auto _ : state) {
    StreamKey key{7, i, pass, 0};
    sum += shading->direct_lighting().estimate(points[i], *shading, Pattern::Random, key);
    if (++i == points.size()) i = 0, ++pass;
  }
  benchmark::DoNotOptimize(sum);
  state.SetItemsProcessed(state.iterations() * shading->direct_lighting().method().total_samples());
}

#define LINE_BENCHES(scene, id)                                                                \
  BENCHMARK_CAPTURE(DirectSample, id##_sa, scene, "sa");                                       \
  BENCHMARK_CAPTURE(DirectSample, id##_bsdf_sa, scene, "bsdf+sa");                             \
  BENCHMARK_CAPTURE(DirectSample, id##_line_area_u, scene, "line-area:u");                     \
  BENCHMARK_CAPTURE(DirectSample, id##_line_sa_v, scene, "line-sa:v");                         \
  BENCHMARK_CAPTURE(DirectSample, id##_line_sa_u_v, scene, "line-sa:u+line-sa:v");             \
  BENCHMARK_CAPTURE(DirectSample, id##_bsdf_line_sa_v, scene, "bsdf+line-sa:v");               \
  BENCHMARK_CAPTURE(DirectSample, id##_bsdf_line_sa_v_smooth, scene, "bsdf+line-sa:v/smooth"); \
  BENCHMARK_CAPTURE(DirectSample, id##_line_bd16_rand, scene, "line-bd16:rand");

LINE_BENCHES("cornell-occluders", cornell)
LINE_BENCHES("monoliths", monoliths)

}  // namespace
}  // namespace penumbra

BENCHMARK_MAIN();
