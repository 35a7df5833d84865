#include "client/scene_checks.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include "core/scene/scene.h"

namespace penumbra {

void report_scene_warnings(const Scene& scene, bool strict, const std::string& scene_path) {
  if (scene.warnings.empty()) return;
  if (strict) {
    std::string list;
    for (const std::string& warning : scene.warnings) list += "\n  " + warning;
    throw FormatError("", scene_path + ": " + std::to_string(scene.warnings.size()) +
                              " warning(s), refused by --strict:" + list);
  }
  const size_t shown = std::min<size_t>(scene.warnings.size(), 20);
  for (size_t i = 0; i < shown; ++i)
    std::fprintf(stderr, "penumbra: warning: %s\n", scene.warnings[i].c_str());
  if (scene.warnings.size() > shown)
    std::fprintf(stderr, "penumbra: warning: ... and %zu more (listed in the output's metadata)\n",
                 scene.warnings.size() - shown);
}

namespace {

std::vector<std::string> compare_reference(const Image& image, const ImageMetadata& metadata,
                                           const std::string& name, const Scene& scene,
                                           bool accept_mismatch) {
  if (image.width != scene.camera.width || image.height != scene.camera.height)
    throw std::runtime_error("reference " + name + " is " + std::to_string(image.width) + "x" +
                             std::to_string(image.height) + ", the scene " + scene.name + " is " +
                             std::to_string(scene.camera.width) + "x" +
                             std::to_string(scene.camera.height));
  std::vector<std::string> warnings;
  auto hash = metadata.find("penumbra:scene_hash");
  if (hash == metadata.end() || hash->second.empty())
    return warnings;  // not ours: nothing to check
  if (hash->second == scene.content_hash) return warnings;
  auto scene_name = metadata.find("penumbra:scene");
  const std::string other =
      "reference " + name + " is of another scene" +
      (scene_name != metadata.end() ? " (" + scene_name->second + ")" : std::string()) +
      ": its scene_hash " + hash->second.substr(0, 12) + " differs from " + scene.name + "'s " +
      scene.content_hash.substr(0, 12);
  if (!accept_mismatch)
    throw std::runtime_error(other +
                             "; errors against it would measure the difference of the scenes "
                             "(--accept-reference-mismatch to use it anyway)");
  warnings.push_back(other + "; accepted by --accept-reference-mismatch");
  return warnings;
}

}  // namespace

CheckedReference check_reference(const std::string& path, const Scene& scene,
                                 bool accept_mismatch) {
  if (!std::filesystem::is_regular_file(path))
    throw std::runtime_error("--reference " + path + ": no such file");
  CheckedReference checked;
  ImageMetadata metadata;
  checked.image = read_exr(path, &metadata);
  checked.warnings = compare_reference(checked.image, metadata, path, scene, accept_mismatch);
  return checked;
}

std::vector<std::string> check_reference_bytes(const std::string& bytes, const std::string& name,
                                               const Scene& scene, bool accept_mismatch) {
  ImageMetadata metadata;
  Image image = decode_exr(bytes, &metadata);
  return compare_reference(image, metadata, name, scene, accept_mismatch);
}

void check_output_path(const std::string& path, const std::vector<std::string>& extensions,
                       const std::string& option) {
  namespace fs = std::filesystem;
  if (path.empty()) throw std::runtime_error(option + ": empty path");
  const fs::path output(path);
  std::string extension = output.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  if (!extensions.empty() &&
      std::find(extensions.begin(), extensions.end(), extension) == extensions.end()) {
    std::string accepted;
    for (const std::string& e : extensions) accepted += (accepted.empty() ? "" : " or ") + e;
    throw std::runtime_error(option + " " + path + ": the output must end in " + accepted +
                             (extension.empty() ? "" : ", not " + extension));
  }
  if (fs::is_directory(output)) throw std::runtime_error(option + " " + path + " is a directory");
  const fs::path folder = output.has_parent_path() ? output.parent_path() : fs::path(".");
  if (!fs::is_directory(folder))
    throw std::runtime_error(option + " " + path + ": the folder " + folder.string() +
                             " does not exist");
  if (access(folder.c_str(), W_OK) != 0)
    throw std::runtime_error(option + " " + path + ": the folder " + folder.string() +
                             " is not writable");
}

}  // namespace penumbra
