#pragma once
// Shared by the farm benchmarks (bench/farm_coordinator_bench.cpp, farm_recovery_bench.cpp): a
// plane under a quad light, cheap to render, as an `sa` job of one pass per task, and a fresh
// folder for a coordinator's data.

#include <cstdint>
#include <filesystem>
#include <random>
#include <string>

#include "penumbra/v1/farm.pb.h"

namespace penumbra::farm::bench {

// A `size` x `size` camera on a lambertian plane lit by a 1 x 1 quad light.
inline std::string plane_scene_json(const std::string& name, int size) {
  return R"({
  "format": "penumbra/scene@1", "name": ")" +
         name + R"(",
  "camera": { "position": [0, 1, 3], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov_y_deg": 40,
              "width": )" +
         std::to_string(size) + R"(, "height": )" + std::to_string(size) + R"( },
  "materials": { "white": { "type": "lambert", "albedo": [0.8, 0.8, 0.8] } },
  "shapes": [ { "type": "quad", "origin": [-2, 0, 2], "edge1": [4, 0, 0], "edge2": [0, 0, -4],
                "material": "white" } ],
  "lights": [ { "type": "quad", "origin": [-0.5, 1.5, -0.5], "edge1": [1, 0, 0],
                "edge2": [0, 0, 1], "radiance": [5, 5, 5] } ]
})";
}

// An `sa` job on that scene: `spp` blocks of one pass per tile of `tile_size`.
inline v1::JobSpec plane_job(const std::string& name, int size, uint32_t spp, uint32_t tile_size) {
  v1::JobSpec spec;
  spec.mutable_scene()->set_scene_json(plane_scene_json(name, size));
  spec.mutable_scene()->set_source_name(name + ".json");
  spec.set_method("sa");
  spec.set_spp(spp);
  spec.set_tile_size(tile_size);
  spec.set_passes_per_task(1);
  return spec;
}

// An empty folder penumbra-bench-<name>-<random> in the temporary directory.
inline std::filesystem::path fresh_dir(const std::string& name) {
  std::random_device random;
  auto dir = std::filesystem::temp_directory_path() /
             ("penumbra-bench-" + name + "-" + std::to_string(random()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace penumbra::farm::bench
