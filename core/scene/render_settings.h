#pragma once
// The render settings a command uses: what its command line (or batch spec) gives wins, then
// what the scene file states (Scene::render_defaults: a pbrt-v3 file's Integrator and Sampler),
// then Penumbra's defaults (method "sa", sampler "stratified", 16 samples per pixel).

#include <cstdint>
#include <string>

#include "core/scene/scene.h"

namespace penumbra {

struct RenderSettings {
  std::string method;   // empty in a request: not given
  std::string sampler;  // empty in a request: not given
  uint32_t spp = 0;     // 0: not given
  double seconds = 0;   // 0: not given
};

inline constexpr const char* kDefaultMethod = "sa";
inline constexpr const char* kDefaultSampler = "stratified";
inline constexpr uint32_t kDefaultSpp = 16;

// Fills what `requested` leaves empty. The budget: a requested spp or seconds wins (both may be
// given); else the scene's seconds (with its spp as the cap, if any) or its spp; else 16 spp.
RenderSettings choose_render_settings(const Scene& scene, const RenderSettings& requested);

}  // namespace penumbra
