// libFuzzer target: the pbrt-v3 reader (core/scene/pbrt_*: tokenizer, parser, scene builder) on
// arbitrary text, through the in-memory package route the coordinator and workers use, with a
// small PLY mesh, an included file and a texture in the package. Every input must either parse
// into a scene that satisfies scene_invariants.h, identically twice, or throw FormatError whose
// message names the place (file:line:column, or the file).

#include <cstddef>
#include <cstdint>
#include <string>

#include "core/scene/scene_package.h"
#include "fuzz/scene_invariants.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace penumbra;
  static const SceneLimits limits = fuzz::fuzz_scene_limits();
  ScenePackage package;
  package.source = "fuzz.pbrt";
  package.scene_json.assign(reinterpret_cast<const char*>(data), size);
  package.files["mesh.ply"] =
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
      "property float z\nproperty float u\nproperty float v\nelement face 1\n"
      "property list uchar int vertex_indices\nend_header\n"
      "0 0 0 0 0\n1 0 0 1 0\n1 1 0 1 1\n0 1 0 0 1\n4 0 1 2 3\n";
  package.files["inc.pbrt"] = "Shape \"trianglemesh\" \"point P\" [0 0 0 1 0 0 0 1 0]\n";
  package.files["tex.tga"] = "not an image";
  Scene scene;
  try {
    scene = parse_scene_package(package, limits);
  } catch (const FormatError& error) {
    std::string message = error.what();
    FUZZ_CHECK(message.find("fuzz.pbrt") != std::string::npos ||
               message.find("inc.pbrt") != std::string::npos ||
               message.find("<pbrt default>") != std::string::npos);
    return 0;
  }
  fuzz::check_scene_invariants(scene, limits);
  FUZZ_CHECK(scene.normals.empty() || scene.normals.size() == scene.positions.size());
  FUZZ_CHECK(scene.uvs.empty() || scene.uvs.size() == scene.positions.size());
  FUZZ_CHECK(parse_scene_package(package, limits).content_hash == scene.content_hash);
  return 0;
}
