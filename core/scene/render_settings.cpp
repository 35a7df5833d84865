#include "core/scene/render_settings.h"

namespace penumbra {

RenderSettings choose_render_settings(const Scene& scene, const RenderSettings& requested) {
  const SceneRenderDefaults& stated = scene.render_defaults;
  RenderSettings chosen = requested;
  if (chosen.method.empty()) chosen.method = stated.method.empty() ? kDefaultMethod : stated.method;
  if (chosen.sampler.empty())
    chosen.sampler = stated.sampler.empty() ? kDefaultSampler : stated.sampler;
  if (requested.spp == 0 && requested.seconds == 0) {
    chosen.seconds = stated.seconds;
    chosen.spp = stated.spp > 0 ? stated.spp : (stated.seconds > 0 ? 0 : kDefaultSpp);
  }
  return chosen;
}

}  // namespace penumbra
