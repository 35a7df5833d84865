#pragma once
// A scene package: a scene file and the OBJ files it names, as bytes, so that a scene can cross
// the network and be parsed where no path a client names is ever opened (the coordinator and
// the workers parse packages; only the client reads files). Parsing a package and loading the
// file it was collected from give the same Scene and the same content hash.
//
// Content hash (Scene::content_hash): SHA-256, as lowercase hex, of the canonical byte string
//   frame(scene JSON text) + for each OBJ file in order of first appearance in `shapes`:
//   frame(normalized relative path) + frame(file bytes)
// where frame(x) is the byte length of x as 8 bytes little-endian followed by x (the lengths
// keep different splits of the same bytes apart).

#include <map>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/scene/scene.h"

namespace penumbra {

struct ScenePackage {
  std::string source;      // a name for error messages (the scene file's path when collected)
  std::string scene_json;  // the scene file's text, byte for byte
  // Normalized relative path (as normalize_scene_relative_path gives) -> the file's bytes.
  std::map<std::string, std::string> files;
};

// Reads a scene file and every OBJ file it names (with the same checks as load_scene: paths
// inside the scene's folder, symlinks resolved, sizes within limits) and parses the scene, so a
// package that is returned is known to load. Throws FormatError.
ScenePackage collect_scene_package(const std::string& path, const SceneLimits& limits = {});

// Parses a scene from a package in memory; never touches the filesystem. OBJ paths are checked
// lexically (no absolute or escaping paths) and looked up in `files`. Files of the package that
// the scene does not name are ignored and do not enter the hash. Throws FormatError.
Scene parse_scene_package(const ScenePackage& package, const SceneLimits& limits = {});

// SHA-256 of `bytes` as 64 lowercase hex digits.
std::string sha256_hex(std::string_view bytes);

// SHA-256 hex of the canonical byte string described above.
std::string scene_content_hash(std::string_view scene_json,
                               const std::vector<std::pair<std::string, std::string>>& obj_files);

}  // namespace penumbra
