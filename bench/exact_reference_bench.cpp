// Cost per shading point of exact direct illumination (core/exact: the shadow-pyramid query over
// the line query's BVH, the visible part of each light by exact integer clipping, Lambert's
// formula over its contours) on every bundled scene where the closed form applies (all lights
// constant polygons). The shading points are the first hits of camera rays through a 48 x 48
// grid of pixel centres that land on Lambertian surfaces: the points an exact reference shades.
// Scenes with other lights (disks, gaussian profiles) are skipped with a note. One thread.
//
// Counters per shading point: candidates (occluder triangles the pyramid query returned),
// projected (those left after clipping to the pyramid and depth slab), contours (of the visible
// part, holes included).
//
//   exact_reference_bench --benchmark_min_time=0.5s

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/exact/exact_shading.h"
#include "core/render/camera.h"
#include "core/scene/scene.h"

namespace penumbra {
namespace {

struct SceneCase {
  std::string name;
  std::shared_ptr<const Scene> scene;
  std::shared_ptr<const ExactShading> exact;
  std::vector<SceneShading::FirstHit> hits;  // Lambertian first hits
};

SceneCase prepare(const std::filesystem::path& path) {
  SceneCase c;
  c.name = path.stem().string();
  c.scene = std::make_shared<const Scene>(load_scene(path.string()));
  c.exact = std::make_shared<const ExactShading>(c.scene);
  if (!c.exact->lights_have_closed_form()) return c;
  const CameraRays camera(c.scene->camera);
  constexpr int kGrid = 48;
  for (int j = 0; j < kGrid; ++j)
    for (int i = 0; i < kGrid; ++i) {
      const double x = (i + 0.5) * c.scene->camera.width / kGrid;
      const double y = (j + 0.5) * c.scene->camera.height / kGrid;
      SceneShading::FirstHit hit =
          c.exact->shading().first_hit(camera.origin(), camera.direction(x, y));
      if (hit.shading_point && hit.shading_point->material &&
          hit.shading_point->material->type == MaterialType::Lambert)
        c.hits.push_back(hit);
    }
  return c;
}

void exact_shading_point(benchmark::State& state, const SceneCase* c) {
  VisibleLightScratch scratch;
  VisibleLightStats stats;
  size_t next = 0;
  double checksum = 0;
  for (auto _ : state) {
    const std::optional<Rgb> value =
        c->exact->exact_radiance(*c->hits[next].shading_point, scratch, &stats);
    checksum += value ? value->x : 0;
    next = next + 1 == c->hits.size() ? 0 : next + 1;
  }
  benchmark::DoNotOptimize(checksum);
  const double points = double(state.iterations());
  state.SetItemsProcessed(state.iterations());
  state.counters["candidates"] = double(stats.candidates) / points;
  state.counters["projected"] = double(stats.projected) / points;
  state.counters["contours"] = double(stats.contours) / points;
  state.counters["triangles"] = double(c->scene->triangle_count());
  state.counters["lights"] = double(c->scene->lights.size());
}

}  // namespace
}  // namespace penumbra

int main(int argc, char** argv) {
  using namespace penumbra;
  benchmark::Initialize(&argc, argv);
  static std::vector<std::unique_ptr<SceneCase>> cases;
  std::vector<std::filesystem::path> paths;
  for (const auto& entry :
       std::filesystem::directory_iterator(std::filesystem::path(PENUMBRA_SOURCE_DIR) / "scenes"))
    if (entry.path().extension() == ".json") paths.push_back(entry.path());
  std::sort(paths.begin(), paths.end());
  for (const auto& path : paths) {
    auto c = std::make_unique<SceneCase>(prepare(path));
    if (!c->exact->lights_have_closed_form()) {
      std::fprintf(stderr,
                   "exact_reference_bench: %s: skipped (a light is not a constant polygon)\n",
                   c->name.c_str());
      continue;
    }
    if (c->hits.empty()) {
      std::fprintf(stderr, "exact_reference_bench: %s: skipped (no Lambertian surface in view)\n",
                   c->name.c_str());
      continue;
    }
    benchmark::RegisterBenchmark(("exact/" + c->name).c_str(), exact_shading_point, c.get())
        ->Unit(benchmark::kMicrosecond);
    cases.push_back(std::move(c));
  }
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
