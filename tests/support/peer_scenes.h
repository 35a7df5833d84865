#pragma once
// Where the peer scenes are (the pbrt-v3 scenes of Salesin & Jarosz's public implementation and
// the seed system's renders): $PENUMBRA_PEER_SCENES, else <repository>/../shared/peer-scenes.
// Tests that need them GTEST_SKIP with this message when they are absent.

#include <cstdlib>
#include <filesystem>
#include <string>

namespace penumbra::testing {

inline std::filesystem::path peer_scenes_dir() {
  if (const char* env = std::getenv("PENUMBRA_PEER_SCENES"); env && *env) return env;
  return std::filesystem::path(PENUMBRA_SOURCE_DIR) / ".." / "shared" / "peer-scenes";
}

// The path of `relative` in the peer scenes, or empty when it is not on this machine.
inline std::string peer_scene(const std::string& relative) {
  std::filesystem::path path = peer_scenes_dir() / relative;
  return std::filesystem::exists(path) ? path.lexically_normal().string() : std::string();
}

inline std::string peer_scene_missing(const std::string& relative) {
  return "peer scene not on this machine: " + (peer_scenes_dir() / relative).string() +
         " (set PENUMBRA_PEER_SCENES to the peer-scenes folder)";
}

}  // namespace penumbra::testing
