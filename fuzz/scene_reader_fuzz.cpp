// libFuzzer target: the scene reader (core/scene) on arbitrary JSON text, through the in-memory
// package route the coordinator and workers use. Every input must either parse into a scene
// that satisfies scene_invariants.h, identically twice, or throw FormatError.

#include <cstddef>
#include <cstdint>
#include <string>

#include "core/scene/scene_package.h"
#include "fuzz/scene_invariants.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace penumbra;
  static const SceneLimits limits = fuzz::fuzz_scene_limits();
  ScenePackage package;
  package.source = "fuzz.json";
  package.scene_json.assign(reinterpret_cast<const char*>(data), size);
  // One small OBJ file, so that scenes naming "mesh.obj" get past the file lookup.
  package.files["mesh.obj"] = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 3 4\n";
  Scene scene;
  try {
    scene = parse_scene_package(package, limits);
  } catch (const FormatError& error) {
    FUZZ_CHECK(std::string(error.what()).find("fuzz.json") != std::string::npos ||
               !error.json_path().empty());
    return 0;
  }
  fuzz::check_scene_invariants(scene, limits);
  FUZZ_CHECK(parse_scene_package(package, limits).content_hash == scene.content_hash);
  return 0;
}
