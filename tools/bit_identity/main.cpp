// bit_identity: renders every scene with every method of a list at a small size and prints one
// SHA-256 per (scene, method) of the rendered tile (sums, sums of squares and counts, bit for
// bit), or of the refusal message where the scene refuses the method. Comparing the output of
// two builds shows whether a change altered any image.
//
//   bit_identity [--width 64] [--height 48] [--spp 8] [--sampler stratified]
//                [--methods tools/bit_identity/methods.txt] [--baseline FILE] SCENE...
//
// With --baseline, compares against an earlier output: prints each line that differs or is
// missing, then "N identical, M different", and exits 1 when M > 0.

#include <openssl/evp.h>

#include <cstdio>
#include <exception>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <tbb/task_arena.h>

#include "core/render/renderer.h"
#include "core/scene/scene.h"

namespace {

std::string sha256_hex(const std::string& bytes) {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  EVP_Digest(bytes.data(), bytes.size(), digest, &length, EVP_sha256(), nullptr);
  static const char* hex = "0123456789abcdef";
  std::string out;
  for (unsigned int i = 0; i < length; ++i) {
    out.push_back(hex[digest[i] >> 4]);
    out.push_back(hex[digest[i] & 15]);
  }
  return out;
}

std::vector<std::string> read_methods(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot read the method list");
  std::vector<std::string> methods;
  std::string line;
  while (std::getline(in, line))
    if (!line.empty() && line[0] != '#') methods.push_back(line);
  return methods;
}

// "scene method" -> hash, from an earlier run's output.
std::map<std::string, std::string> read_baseline(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot read the baseline");
  std::map<std::string, std::string> out;
  std::string scene, method, hash;
  while (in >> scene >> method >> hash) out[scene + " " + method] = hash;
  return out;
}

std::string scene_label(const std::string& path) {
  size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

}  // namespace

int main(int argc, char** argv) {
  using namespace penumbra;
  int width = 64, height = 48;
  uint32_t spp = 8;
  std::string sampler = "stratified", methods_path = "tools/bit_identity/methods.txt", baseline;
  std::vector<std::string> scenes;
  for (int i = 1; i < argc; ++i) {
    std::string arg = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw std::runtime_error(arg + " needs a value");
      return argv[++i];
    };
    if (arg == "--width") width = std::stoi(value());
    else if (arg == "--height") height = std::stoi(value());
    else if (arg == "--spp") spp = uint32_t(std::stoul(value()));
    else if (arg == "--sampler") sampler = value();
    else if (arg == "--methods") methods_path = value();
    else if (arg == "--baseline") baseline = value();
    else scenes.push_back(arg);
  }
  if (scenes.empty()) {
    std::cerr << "usage: bit_identity [--width W] [--height H] [--spp N] [--sampler S] "
                 "[--methods FILE] [--baseline FILE] SCENE...\n";
    return 2;
  }
  auto pattern = parse_pattern(sampler);
  if (!pattern) {
    std::cerr << "unknown sampler " << sampler << "\n";
    return 2;
  }
  std::vector<std::string> methods = read_methods(methods_path);
  std::map<std::string, std::string> expected;
  if (!baseline.empty()) expected = read_baseline(baseline);

  tbb::task_arena arena(2);
  int identical = 0, different = 0;
  for (const std::string& path : scenes) {
    auto scene = std::make_shared<Scene>(load_scene(path));
    // A small image of the same view: the camera keeps its field of view.
    scene->camera.width = width;
    scene->camera.height = height;
    scene->camera.full_width = scene->camera.full_height = 0;
    scene->camera.crop_x = scene->camera.crop_y = 0;
    for (const std::string& method : methods) {
      std::string hash;
      try {
        RenderOptions options;
        options.method = method;
        options.sampler = *pattern;
        options.seed = 1;
        Renderer renderer(scene, options);
        TileRect rect{0, 0, width, height};
        TileAccumulator tile(rect);
        arena.execute([&] { renderer.render_tile(rect, 0, spp, tile); });
        hash = sha256_hex(tile.serialize());
      } catch (const std::exception& error) {
        hash = "refused:" + sha256_hex(error.what()).substr(0, 16);
      }
      std::string key = scene_label(path) + " " + method;
      if (baseline.empty()) {
        std::cout << key << " " << hash << std::endl;
        continue;
      }
      auto it = expected.find(key);
      if (it != expected.end() && it->second == hash) {
        ++identical;
      } else {
        ++different;
        std::cout << "DIFFERENT " << key << " " << hash << " (baseline "
                  << (it == expected.end() ? "missing" : it->second) << ")" << std::endl;
      }
    }
  }
  if (!baseline.empty()) {
    std::cout << identical << " identical, " << different << " different" << std::endl;
    return different > 0 ? 1 : 0;
  }
  return 0;
}
