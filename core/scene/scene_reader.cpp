// parse_scene and load_scene (scene.h): the filesystem route into the scene parser.

#include <filesystem>
#include <stdexcept>

#include "core/scene/scene.h"
#include "core/scene/scene_parser.h"
#include "core/scene/scene_path.h"

namespace penumbra {

ObjFileReader folder_obj_reader(const std::string& base_dir, const SceneLimits& limits) {
  return [base_dir, max_bytes = limits.max_file_bytes](const std::string& relative) {
    return read_file_inside(base_dir, relative, max_bytes);
  };
}

std::string read_scene_text(const std::string& path, const SceneLimits& limits) {
  try {
    return read_whole_file(path, limits.max_json_bytes, "max_json_bytes");
  } catch (const std::invalid_argument& error) {
    throw FormatError("", std::string("cannot load scene: ") + error.what());
  }
}

std::string scene_folder(const std::string& path) {
  std::filesystem::path parent = std::filesystem::path(path).parent_path();
  return parent.empty() ? std::string(".") : parent.string();
}

Scene parse_scene(const std::string& json_text, const std::string& base_dir,
                  const std::string& source, const SceneLimits& limits) {
  return parse_scene_with_reader(json_text, folder_obj_reader(base_dir, limits), source, limits)
      .scene;
}

Scene load_scene(const std::string& path, const SceneLimits& limits) {
  return parse_scene(read_scene_text(path, limits), scene_folder(path), path, limits);
}

}  // namespace penumbra
