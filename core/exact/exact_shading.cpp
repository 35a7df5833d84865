// Closed form or converged fallback per shading point (see the header).

#include "core/exact/exact_shading.h"

#include "core/math/vec.h"
#include "core/method/method.h"

namespace penumbra {

ExactShading::ExactShading(std::shared_ptr<const Scene> scene, const ExactShadingOptions& options)
    : options_(options),
      shading_(scene, parse_method(options.fallback_method)),
      occluders_(*scene) {
  lights_exact_ = !scene->lights.empty();
  for (const Light& light : scene->lights)
    if (light.type == LightType::Disk || light.profile != ProfileType::Constant)
      lights_exact_ = false;
}

std::optional<Rgb> ExactShading::exact_radiance(const ShadingPoint& sp,
                                                VisibleLightScratch& scratch,
                                                VisibleLightStats* stats) const {
  if (!lights_exact_ || !sp.material || sp.material->type != MaterialType::Lambert)
    return std::nullopt;
  Rgb irradiance_over_pi{0, 0, 0};
  for (const Light& light : scene().lights) {
    const double projected = visible_projected_solid_angle(
        sp.position, sp.normal, light.vertices, light.normal, occluders_, scratch, stats);
    irradiance_over_pi += light.radiance * (projected / kPi);
  }
  return sp.material->albedo * irradiance_over_pi;
}

ExactSample ExactShading::radiance(const SceneShading::FirstHit& hit, const StreamKey& key,
                                   VisibleLightScratch& scratch, VisibleLightStats* stats) const {
  if (!hit.shading_point) return {hit.emitted, true};
  if (std::optional<Rgb> exact = exact_radiance(*hit.shading_point, scratch, stats))
    return {*exact, true};
  return {shading_.direct_lighting().estimate(*hit.shading_point, shading_, Pattern::Stratified,
                                              key, options_.fallback_samples),
          false};
}

}  // namespace penumbra
