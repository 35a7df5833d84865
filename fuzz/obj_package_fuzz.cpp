// libFuzzer target: OBJ loading through a scene package (the route of every OBJ file that
// reaches the coordinator or a worker). The input is the OBJ file's bytes; the scene names it
// twice (with a scale and a translation) and a `mtllib` in it must never open a file. Every
// input either parses into a scene that satisfies scene_invariants.h or throws FormatError
// naming the OBJ shape.

#include <cstddef>
#include <cstdint>
#include <string>

#include "core/scene/scene_package.h"
#include "fuzz/scene_invariants.h"

namespace {

constexpr const char* kScene = R"({
  "format": "penumbra/scene@1",
  "camera": {"position": [0, 1, 4], "look_at": [0, 0, 0], "fov_y_deg": 40,
             "width": 8, "height": 8},
  "materials": {"matte": {"type": "lambert", "albedo": [0.5, 0.5, 0.5]}},
  "shapes": [
    {"type": "obj", "file": "meshes/part.obj", "material": "matte"},
    {"type": "obj", "file": "meshes/./part.obj", "material": "matte",
     "scale": [2, 0.5, 1], "translate": [0, 0.25, -1]}
  ],
  "lights": [{"type": "quad", "origin": [-0.5, 2, -0.5], "edge1": [1, 0, 0], "edge2": [0, 0, 1],
              "radiance": [4, 4, 4]}]
})";

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace penumbra;
  static const SceneLimits limits = fuzz::fuzz_scene_limits();
  ScenePackage package;
  package.source = "obj-fuzz.json";
  package.scene_json = kScene;
  package.files["meshes/part.obj"].assign(reinterpret_cast<const char*>(data), size);
  Scene scene;
  try {
    scene = parse_scene_package(package, limits);
  } catch (const FormatError& error) {
    FUZZ_CHECK(error.json_path().rfind("$.shapes[", 0) == 0);
    return 0;
  }
  fuzz::check_scene_invariants(scene, limits);
  return 0;
}
