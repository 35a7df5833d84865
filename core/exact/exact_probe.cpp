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
  size_t exact_points = 0;
  for (size_t i = 0; i < hits.size(); ++i) {
    const StreamKey key{seed, uint64_t(i), 0, 0};
    const ExactSample sample = exact.radiance(hits[i], key, scratch);
    exact_points += sample.exact ? 1 : 0;
    doc["points"].push_back(
        {{"index", i},
         {"radiance", {sample.radiance.x, sample.radiance.y, sample.radiance.z}},
         {"exact", sample.exact}});
  }
  // The marked share: points whose value is the fallback's estimate, not the closed form.
  doc["exact_share"] = hits.empty() ? 1.0 : double(exact_points) / double(hits.size());
  doc["fallback_points"] = hits.size() - exact_points;
  return doc.dump(2);
}

}  // namespace penumbra
