// Load time and peak memory of a scene (default: the peer kitchen, 1.44M triangles in 294 PLY
// files): parse (pbrt-v3 text, PLY meshes, textures read), the Embree BVH, and the line query's
// BVH (the shadow-triangle query of core/lines), each timed in wall and CPU seconds, with the
// process's peak resident memory after each phase. Then, with --render, the CPU time per camera
// sample of each method on 12 tiles spread over the image, one thread.
//
// Run: build/release/bench/scene_load_bench [SCENE] [--render] [--tile=64] [--passes=2]
//      (SCENE defaults to ../shared/peer-scenes/kitchen/kitchen-play.pbrt or
//      $PENUMBRA_PEER_SCENES/kitchen/kitchen-play.pbrt)
// Goal (kitchen): parse + BVH + line-query BVH <= 3 s and <= 1.5 GiB on the 2-core machine.

#include <sys/resource.h>
#include <tbb/task_arena.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "core/lines/line_query.h"
#include "core/render/embree_scene.h"
#include "core/render/renderer.h"
#include "core/scene/scene.h"

namespace {

double wall_now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
double cpu_now() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + ts.tv_nsec * 1e-9;
}
double peak_mib() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss / 1024.0;
}

struct Phase {
  double wall0 = wall_now(), cpu0 = cpu_now();
  void report(const char* name) const {
    std::printf("%-22s %8.3f s wall %8.3f s cpu   peak RSS %7.1f MiB\n", name, wall_now() - wall0,
                cpu_now() - cpu0, peak_mib());
  }
};

}  // namespace

int main(int argc, char** argv) {
  using namespace penumbra;
  std::string path;
  bool render = false;
  int tile = 64, passes = 2;
  for (int i = 1; i < argc; ++i) {
    std::string argument = argv[i];
    if (argument == "--render")
      render = true;
    else if (argument.rfind("--tile=", 0) == 0)
      tile = std::stoi(argument.substr(7));
    else if (argument.rfind("--passes=", 0) == 0)
      passes = std::stoi(argument.substr(9));
    else
      path = argument;
  }
  if (path.empty()) {
    const char* env = std::getenv("PENUMBRA_PEER_SCENES");
    std::filesystem::path peer =
        env && *env ? std::filesystem::path(env)
                    : std::filesystem::path(PENUMBRA_SOURCE_DIR) / ".." / "shared" / "peer-scenes";
    path = (peer / "kitchen" / "kitchen-play.pbrt").lexically_normal().string();
  }
  if (!std::filesystem::exists(path)) {
    std::fprintf(stderr, "scene_load_bench: %s not found\n", path.c_str());
    return 1;
  }
  std::printf("scene %s\n", path.c_str());
  Phase total;
  Phase parse;
  auto scene = std::make_shared<const Scene>(load_scene(path));
  parse.report("parse");
  std::printf("  %zu triangles, %zu vertices, %zu materials, %zu lights, %zu warnings\n",
              scene->triangle_count(), scene->positions.size(), scene->materials.size(),
              scene->lights.size(), scene->warnings.size());
  Phase bvh;
  auto embree = std::make_unique<EmbreeScene>(*scene);
  bvh.report("Embree BVH");
  Phase lines;
  auto line_query = std::make_unique<LineQuery>(*scene);
  lines.report("line-query BVH");
  total.report("total");

  if (render) {
    const std::vector<std::string> methods = {"area",    "sa",        "bsdf",
                                              "bsdf+sa", "line-sa:v", "2*bsdf+2*line-sa:v/balance"};
    // Tiles on a 4 x 3 grid over the image (lit, shadowed and unlit parts alike).
    const Camera& camera = scene->camera;
    std::vector<TileRect> rects;
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 4; ++i) {
        int x = (2 * i + 1) * camera.width / 8 - tile / 2,
            y = (2 * j + 1) * camera.height / 6 - tile / 2;
        rects.push_back({std::max(0, x), std::max(0, y), std::min(camera.width, x + tile),
                         std::min(camera.height, y + tile)});
      }
    tbb::task_arena one_thread(1);
    for (const std::string& method : methods) {
      RenderOptions options;
      options.method = method;
      Renderer renderer(scene, options);
      double cpu = 0, samples = 0;
      for (const TileRect& rect : rects) {
        TileAccumulator out(rect);
        double cpu0 = cpu_now();
        one_thread.execute([&] { renderer.render_tile(rect, 0, uint32_t(passes), out); });
        cpu += cpu_now() - cpu0;
        samples += double(rect.pixel_count()) * passes;
      }
      std::printf("render %-28s %8.2f us cpu per camera sample (12 tiles of %d x %d, %d passes)\n",
                  method.c_str(), 1e6 * cpu / samples, tile, tile, passes);
    }
  }
  return 0;
}
