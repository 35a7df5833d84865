#pragma once
// The `penumbra/scene@1` parser behind parse_scene, load_scene and the package route
// (scene_package.h). It never opens a file itself: OBJ bytes come from a reader callback, so the
// same code serves the filesystem and packages in memory, and both hash the same bytes.

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "core/scene/scene.h"

namespace penumbra {

// Returns the bytes of an OBJ file named by its normalized relative path; throws
// std::invalid_argument saying why it cannot (missing, outside the folder, too large).
using ObjFileReader = std::function<std::string(const std::string& relative_path)>;

struct ParsedScene {
  Scene scene;
  // Each file the scene names (OBJ; pbrt-v3: Include, PLY, image textures), in order of first
  // appearance: (relative path, bytes).
  std::vector<std::pair<std::string, std::string>> obj_files;
};

// Parses and validates a scene, fills every derived field and the content hash. A pbrt-v3 file
// (by the extension of `source`, or by its content: pbrt_scene_builder.h) goes to the pbrt-v3
// reader, whose files (Include, PLY, textures) come through the same reader callback. Throws
// FormatError naming `source` and the JSON path or file:line:column.
ParsedScene parse_scene_with_reader(const std::string& json_text, const ObjFileReader& read_obj,
                                    const std::string& source, const SceneLimits& limits);

// The routes from the filesystem (scene_reader.cpp): OBJ files read from `base_dir` with the
// checks of scene_path.h; the scene file's text (FormatError when unreadable); its folder.
ObjFileReader folder_obj_reader(const std::string& base_dir, const SceneLimits& limits);
std::string read_scene_text(const std::string& path, const SceneLimits& limits);
std::string scene_folder(const std::string& path);

}  // namespace penumbra
