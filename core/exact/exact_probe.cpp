#include "core/exact/exact_probe.h"

#include <nlohmann/json.hpp>

#include "core/sampling/pattern.h"

namespace penumbra {

std::string exact_probe_json(std::shared_ptr<const Scene> scene, const ProbeSpec& probe,
                             const ExactShadingOptions& options, uint64_t seed) {
  const ExactShading exact(scene, options);
  const std::vector<SceneShading::FirstHit> hits = resolve_probe_points(exact.shading(), probe);
  nlohmann::json doc;
  doc["format"] = "penumbra/exact-result@1";
  doc["fallback"] = {{"method", options.fallback_method}, {"samples", options.fallback_samples}};
  doc["points"] = nlohmann::json::array();
  VisibleLightScratch scratch;
  for (size_t i = 0; i < hits.size(); ++i) {
    const StreamKey key{seed, uint64_t(i), 0, 0};
    const ExactSample sample = exact.radiance(hits[i], key, scratch);
    doc["points"].push_back(
        {{"index", i},
         {"radiance", {sample.radiance.x, sample.radiance.y, sample.radiance.z}},
         {"exact", sample.exact}});
  }
  return doc.dump(2);
}

}  // namespace penumbra
