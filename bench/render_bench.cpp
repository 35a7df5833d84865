// Throughput of the point-sampling core on cornell-occluders, one thread:
//   ShadowRay        raw Embree shadow rays (our physical limit)
//   DirectSample/M   one whole direct-light sample of method M at a shading point (strategy
//                    sample, shading, pdfs, MIS and the shadow ray), as a ratio to ShadowRay
//   Render512x16     the whole 512x512, 16 spp render with `sa` (seconds; peak RSS)
//   ShadowRay16, CameraRay1, CameraRay16: the query APIs compared (single rays vs packets)
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

// The same shadow rays as 16-wide packets of neighbouring shading points (rtcOccluded16).
void ShadowRay16(benchmark::State& state) {
  SceneShading shading(bench_scene(), parse_method("sa"));
  const Workload& w = workload(shading);
  RTCScene rtc = shading.embree().rtc_scene();
  const double eps = shading.embree().ray_epsilon();
  size_t base = 0, hits = 0;
  alignas(64) int valid[16];
  for (int k = 0; k < 16; ++k) valid[k] = -1;
  for (auto _ : state) {
    RTCRay16 rays;
    for (int k = 0; k < 16; ++k) {
      size_t i = (base + k) % w.points.size();
      Vec3 o = w.points[i].position + w.points[i].normal * eps;
      Vec3 d = w.light_points[i] - o;
      double len = length(d);
      d = d / len;
      rays.org_x[k] = float(o.x), rays.org_y[k] = float(o.y), rays.org_z[k] = float(o.z);
      rays.dir_x[k] = float(d.x), rays.dir_y[k] = float(d.y), rays.dir_z[k] = float(d.z);
      rays.tnear[k] = 0, rays.tfar[k] = float(len - eps), rays.mask[k] = ~0u;
      rays.time[k] = 0, rays.flags[k] = 0, rays.id[k] = k;
    }
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    rtcOccluded16(valid, rtc, &context, &rays);
    for (int k = 0; k < 16; ++k) hits += rays.tfar[k] < 0;
    base += 16;
  }
  benchmark::DoNotOptimize(hits);
  state.SetItemsProcessed(state.iterations() * 16);
}
BENCHMARK(ShadowRay16);

// Camera rays: single rays against 16-wide packets on 4x4 pixel blocks.
void CameraRay1(benchmark::State& state) {
  SceneShading shading(bench_scene(), parse_method("sa"));
  CameraRays camera(shading.scene().camera);
  int x = 0, y = 0, hits = 0;
  for (auto _ : state) {
    hits += bool(shading.embree().intersect(camera.origin(), camera.direction(x + 0.5, y + 0.5)));
    if (++x == shading.scene().camera.width) x = 0, y = (y + 1) % shading.scene().camera.height;
  }
  benchmark::DoNotOptimize(hits);
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(CameraRay1);

void CameraRay16(benchmark::State& state) {
  SceneShading shading(bench_scene(), parse_method("sa"));
  const Camera& cam = shading.scene().camera;
  CameraRays camera(cam);
  RTCScene rtc = shading.embree().rtc_scene();
  alignas(64) int valid[16];
  for (int k = 0; k < 16; ++k) valid[k] = -1;
  int bx = 0, by = 0, hits = 0;
  for (auto _ : state) {
    RTCRayHit16 rh;
    for (int k = 0; k < 16; ++k) {
      Vec3 d = camera.direction(bx + (k % 4) + 0.5, by + (k / 4) + 0.5);
      rh.ray.org_x[k] = float(camera.origin().x), rh.ray.org_y[k] = float(camera.origin().y);
      rh.ray.org_z[k] = float(camera.origin().z);
      rh.ray.dir_x[k] = float(d.x), rh.ray.dir_y[k] = float(d.y), rh.ray.dir_z[k] = float(d.z);
      rh.ray.tnear[k] = 0, rh.ray.tfar[k] = 1e30f, rh.ray.mask[k] = ~0u, rh.ray.time[k] = 0;
      rh.ray.flags[k] = 0, rh.ray.id[k] = k, rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
    }
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    rtcIntersect16(valid, rtc, &context, &rh);
    for (int k = 0; k < 16; ++k) hits += rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID;
    bx += 4;
    if (bx >= cam.width) bx = 0, by = (by + 4) % (cam.height - 3);
  }
  benchmark::DoNotOptimize(hits);
  state.SetItemsProcessed(state.iterations() * 16);
}
BENCHMARK(CameraRay16);

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
  state.SetItemsProcessed(state.iterations() * shading.direct_lighting().method().total_samples());
}
BENCHMARK_CAPTURE(DirectSample, sa, "sa");
BENCHMARK_CAPTURE(DirectSample, area, "area");
BENCHMARK_CAPTURE(DirectSample, bsdf, "bsdf");
BENCHMARK_CAPTURE(DirectSample, bsdf_sa_balance, "bsdf+sa/balance");
BENCHMARK_CAPTURE(DirectSample, psa, "psa");

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
