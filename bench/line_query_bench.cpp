// Line query throughput against Embree shadow rays, on the same shading points and light.
//
// Scenes (PERFORMANCE.md): S1 cornell-occluders (scenes/cornell-occluders.json, or a Cornell
// box with 20 floating boxes built here when the file is missing or does not load); S3 = S1 plus
// a ~1M-triangle UV sphere; S2 = S1 plus 1M small random triangles; the kitchen
// (../shared/peer-scenes/kitchen/kitchen-play.pbrt, 1.44M triangles, its window light; skipped
// when absent). Shading points are the first
// hits of camera rays (Embree rtcIntersect1) that face the light; per shading point 16 random
// light samples: a point on the quad light for the shadow ray (rtcOccluded1, tnear/tfar set to
// the line query's own tolerances) and a line along edge1 at a random offset for the line query.
//
// Each benchmark reports CPU time per query on one thread; the summary printed at the end gives
// the ratio line query / shadow ray per scene, measured in the same run (figures on these shared
// machines drift by ~25% hour to hour; ratios in one run do not).
//
// Run: build-*/bench/line_query_bench [--benchmark_filter=S1] [--benchmark_repetitions=5]
//      [--bundled]     (also every bundled scene with a quad light: shadow_ray and
//                       line_query_medium on scene:<file stem>, e.g. --benchmark_filter=scene:)
//      [--scene=PATH]  (also any scene file, e.g. a pbrt-v3 file: shadow_ray and
//                       line_query_medium on file:<path>)
//      [--queries=N]   (a fixed number of iterations per benchmark: repeatable instruction
//                       counts under callgrind, e.g.
//   valgrind --tool=callgrind --toggle-collect='penumbra::LineQuery::visible_intervals*'
//     build-*/bench/line_query_bench --benchmark_filter=line_query_medium/S1 --queries=12000
//   and divide the instructions by the iterations plus the brute-force checks, 256 on S1)

#include <benchmark/benchmark.h>
#include <embree3/rtcore.h>
#include <pmmintrin.h>
#include <xmmintrin.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "core/lines/line_query.h"
#include "core/lines/occluder_meshes.h"
#include "core/scene/scene.h"

namespace penumbra {
namespace {

using namespace occluder_meshes;

struct QuadLight {
  Vec3 origin, edge1, edge2;
};

struct BenchScene {
  std::string name;
  std::string description;
  TriangleMesh mesh;
  QuadLight light;
  Camera camera;
};

// S1. The bundled scene when it loads, otherwise a Cornell box of the same size with 20
// floating boxes.
BenchScene cornell_occluders() {
  BenchScene scene;
  scene.name = "S1";
  std::string path = std::string(PENUMBRA_SOURCE_DIR) + "/scenes/cornell-occluders.json";
  try {
    Scene loaded = load_scene(path);
    if (!loaded.lights.empty() && loaded.lights[0].type == LightType::Quad) {
      scene.mesh.positions = loaded.positions;
      scene.mesh.indices = loaded.indices;
      scene.light = {loaded.lights[0].origin, loaded.lights[0].edge1, loaded.lights[0].edge2};
      scene.camera = loaded.camera;
      scene.description = "scenes/cornell-occluders.json";
      return scene;
    }
  } catch (const std::exception& error) {
    std::fprintf(stderr, "line_query_bench: %s does not load (%s); building S1 in code\n",
                 path.c_str(), error.what());
  }
  scene.description = "cornell box with 20 floating boxes, built in code";
  // Room [-1,1] x [0,2] x [-1,1], open towards +z (the camera).
  auto add_quad = [&](const Vec3& origin, const Vec3& u, const Vec3& v) {
    uint32_t base = static_cast<uint32_t>(scene.mesh.positions.size());
    scene.mesh.positions.insert(scene.mesh.positions.end(),
                                {origin, origin + u, origin + u + v, origin + v});
    scene.mesh.add_triangle(base, base + 1, base + 2);
    scene.mesh.add_triangle(base, base + 2, base + 3);
  };
  add_quad({-1, 0, -1}, {2, 0, 0}, {0, 0, 2});  // floor
  add_quad({-1, 2, -1}, {2, 0, 0}, {0, 0, 2});  // ceiling
  add_quad({-1, 0, -1}, {2, 0, 0}, {0, 2, 0});  // back
  add_quad({-1, 0, -1}, {0, 0, 2}, {0, 2, 0});  // left
  add_quad({1, 0, -1}, {0, 0, 2}, {0, 2, 0});   // right
  std::mt19937_64 rng(20);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int i = 0; i < 20; ++i) {
    Vec3 center(-0.7 + 1.4 * unit(rng), 0.9 + 0.6 * unit(rng), -0.6 + 1.2 * unit(rng));
    Vec3 half(0.05 + 0.1 * unit(rng), 0.02 + 0.02 * unit(rng), 0.05 + 0.1 * unit(rng));
    scene.mesh.append(box_mesh(center - half, center + half));
  }
  scene.light = {{-0.24, 1.98, -0.22}, {0.47, 0, 0}, {0, 0, 0.38}};
  scene.camera.position = {0, 1, 6.8};
  scene.camera.look_at = {0, 1, 0};
  scene.camera.fov_y_deg = 19.5;
  scene.camera.width = scene.camera.height = 512;
  return scene;
}

BenchScene with_sphere() {
  BenchScene scene = cornell_occluders();
  scene.name = "S3";
  scene.description = "S1 + UV sphere of ~1M triangles";
  scene.mesh.append(uv_sphere_mesh({0.05, 0.55, -0.1}, 0.35, 500, 1000));
  return scene;
}

BenchScene with_random_triangles() {
  BenchScene scene = cornell_occluders();
  scene.name = "S2";
  scene.description = "S1 + 1M random triangles (size 0.006) in [-1,1]x[0.1,1.9]x[-1,1]";
  scene.mesh.append(random_triangles_mesh(1'000'000, {-1, 0.1, -1}, {1, 1.9, 1}, 0.006, 99));
  return scene;
}

BenchScene from_loaded(BenchScene scene, const Scene& loaded) {
  for (const Light& light : loaded.lights) {
    if (light.type != LightType::Quad) continue;
    scene.mesh.positions = loaded.positions;
    scene.mesh.indices = loaded.indices;
    scene.light = {light.origin, light.edge1, light.edge2};
    scene.camera = loaded.camera;
    return scene;
  }
  throw std::runtime_error(scene.description + " has no quad light");
}

// A bundled scene by file stem ("scene:<stem>"), or any scene file by its path ("file:<path>",
// e.g. a pbrt-v3 file): its triangles, first quad light and camera.
BenchScene bundled_scene(const std::string& stem) {
  BenchScene scene;
  scene.name = "scene:" + stem;
  scene.description = "scenes/" + stem + ".json";
  Scene loaded = load_scene(std::string(PENUMBRA_SOURCE_DIR) + "/" + scene.description);
  return from_loaded(std::move(scene), loaded);
}

BenchScene file_scene(const std::string& path) {
  BenchScene scene;
  scene.name = "file:" + path;
  scene.description = path;
  return from_loaded(std::move(scene), load_scene(path));
}
// The papers' kitchen (1.44M triangles, a window light), when ../shared/peer-scenes is there.
std::string kitchen_path() {
  return std::string(PENUMBRA_SOURCE_DIR) + "/../shared/peer-scenes/kitchen/kitchen-play.pbrt";
}

BenchScene make_scene(const std::string& name) {
  if (name == "kitchen") {
    BenchScene scene = file_scene(kitchen_path());
    scene.name = name;
    scene.description = "peer-scenes/kitchen/kitchen-play.pbrt";
    return scene;
  }
  if (name.rfind("scene:", 0) == 0) return bundled_scene(name.substr(6));
  if (name.rfind("file:", 0) == 0) return file_scene(name.substr(5));
  if (name == "S3") return with_sphere();
  if (name == "S2") return with_random_triangles();
  return cornell_occluders();
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// A scene ready to query: the Embree scene for rays, both line-query builds, and the queries.
struct Prepared {
  BenchScene scene;
  RTCDevice device = nullptr;
  RTCScene rtc_scene = nullptr;
  std::map<LineQueryBuildQuality, std::unique_ptr<LineQuery>> line_queries;
  std::map<LineQueryBuildQuality, double> build_seconds;
  double embree_build_seconds = 0;
  struct Query {
    Vec3 x;
    Vec3 light_point;     // shadow ray target
    Vec3 line_a, line_b;  // line sample
  };
  std::vector<Query> queries;

  explicit Prepared(const std::string& name) : scene(make_scene(name)) {
    device = rtcNewDevice(nullptr);
    auto start = std::chrono::steady_clock::now();
    rtc_scene = rtcNewScene(device);
    RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* vertices = static_cast<float*>(
        rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                3 * sizeof(float), scene.mesh.positions.size()));
    for (size_t i = 0; i < scene.mesh.positions.size(); ++i)
      for (int k = 0; k < 3; ++k)
        vertices[3 * i + k] = static_cast<float>(scene.mesh.positions[i][k]);
    auto* triangles = static_cast<uint32_t*>(
        rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                3 * sizeof(uint32_t), scene.mesh.triangle_count()));
    std::copy(scene.mesh.indices.begin(), scene.mesh.indices.end(), triangles);
    rtcCommitGeometry(geometry);
    rtcAttachGeometry(rtc_scene, geometry);
    rtcReleaseGeometry(geometry);
    rtcSetSceneBuildQuality(rtc_scene, RTC_BUILD_QUALITY_MEDIUM);
    rtcCommitScene(rtc_scene);
    embree_build_seconds = seconds_since(start);
    make_queries();
  }
  ~Prepared() {
    rtcReleaseScene(rtc_scene);
    rtcReleaseDevice(device);
  }

  const LineQuery& line_query(LineQueryBuildQuality quality) {
    auto& slot = line_queries[quality];
    if (!slot) {
      LineQueryOptions options;
      options.build_quality = quality;
      auto start = std::chrono::steady_clock::now();
      slot = std::make_unique<LineQuery>(scene.mesh.positions, scene.mesh.indices, options);
      build_seconds[quality] = seconds_since(start);
    }
    return *slot;
  }

  void make_queries() {
    const Camera& camera = scene.camera;
    Vec3 forward = normalize(camera.look_at - camera.position);
    Vec3 right = normalize(cross(forward, camera.up));
    Vec3 up = cross(right, forward);
    double tan_half = std::tan(0.5 * camera.fov_y_deg * kPi / 180);
    double aspect = static_cast<double>(camera.width) / camera.height;
    std::mt19937_64 rng(1234);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    const QuadLight& light = scene.light;
    Vec3 light_center = light.origin + 0.5 * light.edge1 + 0.5 * light.edge2;
    const int shading_points = 4096, samples_per_point = 16;
    int attempts = 0;
    while (queries.size() < static_cast<size_t>(shading_points * samples_per_point) &&
           attempts++ < 100 * shading_points) {
      // A camera ray through a random pixel.
      double px = (2 * unit(rng) - 1) * tan_half * aspect, py = (1 - 2 * unit(rng)) * tan_half;
      Vec3 direction = normalize(forward + px * right + py * up);
      RTCIntersectContext context;
      rtcInitIntersectContext(&context);
      RTCRayHit hit{};
      hit.ray.org_x = static_cast<float>(camera.position.x);
      hit.ray.org_y = static_cast<float>(camera.position.y);
      hit.ray.org_z = static_cast<float>(camera.position.z);
      hit.ray.dir_x = static_cast<float>(direction.x);
      hit.ray.dir_y = static_cast<float>(direction.y);
      hit.ray.dir_z = static_cast<float>(direction.z);
      hit.ray.tnear = 0;
      hit.ray.tfar = 1e30f;
      hit.ray.mask = ~0u;
      hit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
      rtcIntersect1(rtc_scene, &context, &hit);
      if (hit.hit.geomID == RTC_INVALID_GEOMETRY_ID) continue;
      Vec3 normal = normalize(Vec3(hit.hit.Ng_x, hit.hit.Ng_y, hit.hit.Ng_z));
      if (dot(normal, direction) > 0) normal = -normal;
      Vec3 x = camera.position + static_cast<double>(hit.ray.tfar) * direction + 1e-4 * normal;
      if (dot(normal, light_center - x) <= 0) continue;  // light below the horizon
      for (int s = 0; s < samples_per_point; ++s) {
        Query query;
        query.x = x;
        query.light_point = light.origin + unit(rng) * light.edge1 + unit(rng) * light.edge2;
        query.line_a = light.origin + unit(rng) * light.edge2;
        query.line_b = query.line_a + light.edge1;
        queries.push_back(query);
      }
    }
  }
};

std::unique_ptr<Prepared> current;
// The prepared scene, or null (with the benchmark skipped) when it does not load.
Prepared* prepare(benchmark::State& state, const std::string& name) {
  if (!current || current->scene.name != name) {
    current.reset();  // one large scene in memory at a time
    try {
      current = std::make_unique<Prepared>(name);
    } catch (const std::exception& error) {
      state.SkipWithError(error.what());
      return nullptr;
    }
  }
  if (current->queries.empty()) {
    state.SkipWithError("no shading point sees the light");
    return nullptr;
  }
  return current.get();
}

void shadow_rays(benchmark::State& state, const std::string& name) {
  Prepared* loaded = prepare(state, name);
  if (!loaded) return;
  Prepared& prepared = *loaded;
  const ShadowTriangleTolerances tolerances;
  size_t i = 0, occluded = 0, count = 0;
  for (auto _ : state) {
    const Prepared::Query& query = prepared.queries[i];
    if (++i == prepared.queries.size()) i = 0;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRay ray{};
    ray.org_x = static_cast<float>(query.x.x);
    ray.org_y = static_cast<float>(query.x.y);
    ray.org_z = static_cast<float>(query.x.z);
    Vec3 direction = query.light_point - query.x;  // unnormalized: t in [0,1] spans x -> light
    ray.dir_x = static_cast<float>(direction.x);
    ray.dir_y = static_cast<float>(direction.y);
    ray.dir_z = static_cast<float>(direction.z);
    ray.tnear = static_cast<float>(tolerances.self_occlusion_epsilon);
    ray.tfar = static_cast<float>(1 - tolerances.light_plane_epsilon);
    ray.mask = ~0u;
    rtcOccluded1(prepared.rtc_scene, &context, &ray);
    occluded += ray.tfar < 0;
    ++count;
  }
  state.counters["occluded"] = static_cast<double>(occluded) / std::max<size_t>(count, 1);
  state.counters["triangles"] = static_cast<double>(prepared.scene.mesh.triangle_count());
  state.counters["build_ms"] = 1e3 * prepared.embree_build_seconds;
  state.SetItemsProcessed(state.iterations());
  state.SetLabel(prepared.scene.description);
}

void line_queries(benchmark::State& state, const std::string& name, LineQueryBuildQuality quality) {
  Prepared* loaded = prepare(state, name);
  if (!loaded) return;
  Prepared& prepared = *loaded;
  const LineQuery& line_query = prepared.line_query(quality);
  // Measure only a query that gives the right answer: a sample against the brute force.
  size_t checks = prepared.scene.mesh.triangle_count() > 100'000 ? 8 : 256;
  for (size_t i = 0; i < checks && i < prepared.queries.size(); ++i) {
    const Prepared::Query& query = prepared.queries[i * 97 % prepared.queries.size()];
    IntervalList expected, actual;
    visible_intervals_brute_force(prepared.scene.mesh.positions, prepared.scene.mesh.indices,
                                  query.x, query.line_a, query.line_b, expected);
    line_query.visible_intervals(query.x, query.line_a, query.line_b, actual);
    bool same = expected.size() == actual.size();
    for (size_t k = 0; same && k < actual.size(); ++k)
      same = std::fabs(expected[k].lo - actual[k].lo) <= 1e-6 &&
             std::fabs(expected[k].hi - actual[k].hi) <= 1e-6;
    if (!same) {
      state.SkipWithError("line query differs from the brute force");
      return;
    }
  }
  IntervalList visible;
  LineQueryStats stats;
  size_t i = 0, fully_occluded = 0, count = 0, pieces = 0;
  double visible_length = 0;
  for (auto _ : state) {
    const Prepared::Query& query = prepared.queries[i];
    if (++i == prepared.queries.size()) i = 0;
    line_query.visible_intervals(query.x, query.line_a, query.line_b, visible, &stats);
    benchmark::DoNotOptimize(visible.size());
    fully_occluded += visible.fully_occluded();
    pieces += visible.size();
    visible_length += visible.visible_length();
    ++count;
  }
  double n = static_cast<double>(std::max<size_t>(count, 1));
  state.counters["fully_occluded"] = fully_occluded / n;
  state.counters["mean_visible"] = visible_length / n;
  state.counters["pieces"] = pieces / n;
  state.counters["nodes"] = stats.nodes_visited / n;
  state.counters["tri_tests"] = stats.triangles_tested / n;
  state.counters["cuts"] = stats.cuts / n;
  state.counters["build_ms"] = 1e3 * prepared.build_seconds[quality];
  state.SetItemsProcessed(state.iterations());
}

// Collects CPU time per query by benchmark name and prints the ratios at the end.
class RatioReporter : public benchmark::ConsoleReporter {
 public:
  std::vector<std::string> scenes;  // in the order of the summary

  void ReportRuns(const std::vector<Run>& runs) override {
    ConsoleReporter::ReportRuns(runs);
    for (const Run& run : runs) {
      if (run.run_type == Run::RT_Aggregate && run.aggregate_name != "median") continue;
      std::string name = run.run_name.function_name;
      double ns = run.GetAdjustedCPUTime();  // time unit: ns (set below)
      nanoseconds_[name] = ns;
    }
  }
  void print_summary() const {
    std::printf("\nPer query, one thread, CPU time (median when repeated):\n");
    std::printf("%-28s %13s %14s %14s %7s %14s %7s\n", "scene", "shadow ray ns", "line medium ns",
                "medium q/s", "ratio", "line high ns", "ratio");
    auto find = [&](const std::string& key) {
      auto found = nanoseconds_.find(key);
      return found == nanoseconds_.end() ? -1.0 : found->second;
    };
    std::vector<std::pair<double, std::string>> bundled;  // medium ratio, scene
    for (const std::string& scene : scenes) {
      double ray = find("shadow_ray/" + scene);
      double medium = find("line_query_medium/" + scene);
      double high = find("line_query_high/" + scene);
      if (ray <= 0 || medium <= 0) continue;
      std::printf("%-28s %13.1f %14.1f %14.0f %7.2f", scene.c_str(), ray, medium, 1e9 / medium,
                  medium / ray);
      if (high > 0) {
        std::printf(" %14.1f %7.2f\n", high, high / ray);
      } else {
        std::printf(" %14s %7s\n", "-", "-");
      }
      if (scene.rfind("scene:", 0) == 0) bundled.emplace_back(medium / ray, scene);
    }
    if (bundled.empty()) return;
    // The distribution over the bundled scenes (medium build).
    std::sort(bundled.begin(), bundled.end());
    const auto& median = bundled[bundled.size() / 2];
    std::printf(
        "\nLine query / shadow ray over %zu bundled scenes (medium build): min %.2f (%s), "
        "median %.2f (%s), max %.2f (%s)\n",
        bundled.size(), bundled.front().first, bundled.front().second.c_str(), median.first,
        median.second.c_str(), bundled.back().first, bundled.back().second.c_str());
  }

 private:
  std::map<std::string, double> nanoseconds_;
};

}  // namespace
}  // namespace penumbra

int main(int argc, char** argv) {
  using namespace penumbra;
  // --queries=N: fixed iterations; --bundled: also every bundled scene with a quad light
  // (line_query_medium only). Removed before Google Benchmark parses the rest.
  long fixed_iterations = 0;
  bool bundled = false;
  std::vector<std::string> files;  // --scene=PATH: any scene file (JSON or pbrt-v3)
  for (int i = 1; i < argc; ++i) {
    std::string argument(argv[i]);
    if (argument == "--bundled") {
      bundled = true;
    } else if (argument.rfind("--scene=", 0) == 0) {
      files.push_back(argument.substr(8));
    } else if (argument.rfind("--queries=", 0) == 0) {
      fixed_iterations = std::stol(argument.substr(10));
    } else {
      continue;
    }
    for (int j = i; j + 1 < argc; ++j) argv[j] = argv[j + 1];
    --argc;
    --i;
  }
  auto fix = [&](benchmark::internal::Benchmark* benchmark) {
    benchmark->Unit(benchmark::kNanosecond);
    if (fixed_iterations > 0) benchmark->Iterations(fixed_iterations);
  };
  // Flush-to-zero and denormals-are-zero, as every render thread sets them.
  _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
  _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
  RatioReporter reporter;
  // A scene's shadow-ray and line-query benchmarks (the High build too when asked), in the
  // ratio summary.
  auto register_scene = [&](const std::string& name, bool high) {
    reporter.scenes.push_back(name);
    fix(benchmark::RegisterBenchmark(
        ("shadow_ray/" + name).c_str(),
        [name](benchmark::State& state) { shadow_rays(state, name); }));
    fix(benchmark::RegisterBenchmark(("line_query_medium/" + name).c_str(),
                                     [name](benchmark::State& state) {
                                       line_queries(state, name, LineQueryBuildQuality::Medium);
                                     }));
    if (high)
      fix(benchmark::RegisterBenchmark(("line_query_high/" + name).c_str(),
                                       [name](benchmark::State& state) {
                                         line_queries(state, name, LineQueryBuildQuality::High);
                                       }));
  };
  for (const char* scene : {"S1", "S3", "S2"}) register_scene(scene, true);
  if (std::filesystem::exists(kitchen_path())) {
    register_scene("kitchen", false);
  } else {
    std::fprintf(stderr, "line_query_bench: %s is absent: no kitchen benchmarks\n",
                 kitchen_path().c_str());
  }
  if (bundled) {
    std::vector<std::string> stems;
    for (const auto& entry :
         std::filesystem::directory_iterator(std::string(PENUMBRA_SOURCE_DIR) + "/scenes"))
      if (entry.path().extension() == ".json") stems.push_back(entry.path().stem().string());
    std::sort(stems.begin(), stems.end());
    for (const std::string& stem : stems) register_scene("scene:" + stem, true);
  }
  for (const std::string& path : files) register_scene("file:" + path, false);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  reporter.print_summary();
  benchmark::Shutdown();
  current.reset();
  return 0;
}
