#pragma once
// Helpers for the batch tests: a tiny scene with a glossy (GGX) floor, a spec around it, and
// submitting and watching a batch through the client (proto/support/batch_client.h).

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>

#include "proto/support/batch_client.h"

namespace penumbra::farm::testing {

// size x size (default 48): a GGX floor (line-bd16 refuses it), a box occluder and a quad light.
inline std::string write_batch_scene(const std::filesystem::path& dir, int size = 48) {
  std::filesystem::path path = dir / "batch-test.json";
  std::ofstream(path) << R"({
  "format": "penumbra/scene@1",
  "name": "batch-test",
  "camera": { "position": [0, 1.2, 3.0], "look_at": [0, 0.3, 0], "up": [0, 1, 0],
              "fov_y_deg": 40, "width": )"
                      << size << R"(, "height": )" << size << R"( },
  "materials": { "floor": { "type": "ggx", "diffuse": [0.5, 0.5, 0.5], "specular": [0.3, 0.3, 0.3],
                            "roughness": 0.3 },
                 "red": { "type": "lambert", "albedo": [0.7, 0.1, 0.1] } },
  "shapes": [
    { "type": "quad", "origin": [-2, 0, 2], "edge1": [4, 0, 0], "edge2": [0, 0, -4], "material": "floor" },
    { "type": "box", "min": [-0.3, 0.4, -0.3], "max": [0.3, 0.5, 0.3], "material": "red" }
  ],
  "lights": [
    { "type": "quad", "origin": [-0.5, 1.5, -0.5], "edge1": [1, 0, 0], "edge2": [0, 0, 1],
      "radiance": [5, 5, 5] }
  ],
  "regions": { "shadow": [)"
                      << size / 4 << ", " << size * 5 / 12 << ", " << size * 3 / 4 << ", "
                      << size * 5 / 6 << R"(] }
})";
  return path.string();
}

inline v1::SubmitBatchRequest batch_request(const std::filesystem::path& dir,
                                            const std::string& spec_json) {
  return make_batch_request_from_text(spec_json, (dir / "spec.json").string(), dir.string(),
                                      [](const std::string& name) { return name + ".json"; });
}

inline v1::BatchStatus run_to_end(BatchClient& client, const std::string& batch_id,
                                  std::chrono::seconds timeout = std::chrono::seconds(300)) {
  return client.watch(batch_id, {}, timeout);
}

}  // namespace penumbra::farm::testing
