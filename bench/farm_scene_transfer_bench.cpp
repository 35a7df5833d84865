// A big scene through the farm: the kitchen of Salesin & Jarosz (../shared/peer-scenes/kitchen,
// 1.44M triangles, ~59 MiB with its PLY meshes and textures) uploaded in chunks to an embedded
// coordinator, uploaded again (nothing is sent), and rendered at 1 spp of `bsdf` on two workers;
// the image must be bit-identical to a local render of the same file (the program fails if it
// is not). Counters: the package's size and chunks, the upload's wall seconds, and the render's.
// Too slow for a unit test (a few parses and BVH builds of the kitchen, ~30-60 s of CPU).
//
// Linked with penumbra_farm by server/CMakeLists.txt; without the farm it only says so.
#if __has_include("penumbra/v1/farm.grpc.pb.h")
#include <benchmark/benchmark.h>

#include <cstring>
#include <filesystem>

#include "core/render/film.h"
#include "core/render/renderer.h"
#include "proto/support/scene_chunks.h"
#include "proto/support/scene_packing.h"
#include "server/embedded_farm.h"

namespace penumbra::farm {
namespace {

std::string kitchen_path() {
  const char* env = std::getenv("PENUMBRA_PEER_SCENES");
  std::filesystem::path dir =
      env && *env ? std::filesystem::path(env)
                  : std::filesystem::path(PENUMBRA_SOURCE_DIR) / ".." / "shared" / "peer-scenes";
  return (dir / "kitchen" / "kitchen-play.pbrt").lexically_normal().string();
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void BM_KitchenThroughTheFarm(benchmark::State& state) {
  const std::string path = kitchen_path();
  if (!std::filesystem::exists(path)) {
    state.SkipWithError(("peer scene not on this machine: " + path).c_str());
    return;
  }
  const v1::ScenePackage package = pack_scene_file(path);
  const Scene scene = parse_wire_package(package);
  EmbeddedFarmOptions options;
  options.workers = 2;
  EmbeddedFarm farm(options);
  for (auto _ : state) {
    auto start = std::chrono::steady_clock::now();
    SceneUploadResult upload = farm.client().upload_scene(package, scene.content_hash);
    state.counters["upload_s"] = seconds_since(start);
    state.counters["chunks"] = upload.chunks_total;
    state.counters["chunks_sent"] = upload.chunks_sent;
    start = std::chrono::steady_clock::now();
    SceneUploadResult again = farm.client().upload_scene(package, scene.content_hash);
    state.counters["upload_again_s"] = seconds_since(start);
    state.counters["chunks_sent_again"] = again.chunks_sent;

    v1::JobSpec spec;
    spec.set_scene_hash(scene.content_hash);
    spec.set_method("bsdf");
    spec.set_sampler("stratified");
    spec.set_seed(1);
    spec.set_spp(1);
    spec.set_passes_per_task(1);
    spec.set_tile_size(128);
    start = std::chrono::steady_clock::now();
    Film film = farm.run(spec);
    state.counters["farm_render_s"] = seconds_since(start);

    RenderOptions render_options;
    render_options.method = "bsdf";
    render_options.seed = 1;
    Renderer renderer(std::make_shared<const Scene>(scene), render_options);
    std::vector<TileAccumulator> tiles;
    for (const TileRect& rect : cut_tiles(scene.camera.width, scene.camera.height, 64)) {
      tiles.emplace_back(rect);
      renderer.render_tile(rect, 0, 1, tiles.back());
    }
    Film local = assemble_film(scene.camera.width, scene.camera.height, tiles);
    const bool same = film.color.rgb.size() == local.color.rgb.size() &&
                      std::memcmp(film.color.rgb.data(), local.color.rgb.data(),
                                  local.color.rgb.size() * sizeof(float)) == 0;
    state.counters["bit_identical"] = same ? 1 : 0;
    if (!same) state.SkipWithError("the farm's image differs from the local render");
  }
  state.counters["package_mib"] = double(serialize_package(package).size()) / double(1 << 20);
}
BENCHMARK(BM_KitchenThroughTheFarm)->Iterations(1)->Unit(benchmark::kSecond);

}  // namespace
}  // namespace penumbra::farm

BENCHMARK_MAIN();
#else
#include <cstdio>
int main() {
  std::puts("farm_scene_transfer_bench: configured with PENUMBRA_FARM=OFF");
  return 0;
}
#endif
