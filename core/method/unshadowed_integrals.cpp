#include "core/method/unshadowed_integrals.h"

namespace penumbra {

Rgb diffuse_albedo(const Material* material) {
  if (!material) return {0, 0, 0};
  switch (material->type) {
    case MaterialType::Lambert:
      return material->albedo;
    case MaterialType::Phong:
      return material->kd;
    case MaterialType::Ggx:
      return material->diffuse;
    default:
      break;
  }
  return {0, 0, 0};
}

UnshadowedIntegrals unshadowed_polygon_shading(const ShadingPoint& sp, const Light& light,
                                               const ProjectedSolidAngleStrategy& psa,
                                               const LtcStrategy& ltc) {
  Rgb a0 = diffuse_albedo(sp.material);
  for (int channel = 0; channel < 3; ++channel)
    a0[channel] = std::max(a0[channel], kMinDiffuseAlbedoForWeights);
  Rgb radiance = light.radiance;
  return {radiance * a0 * (psa.projected_solid_angle() * kInvPi),
          radiance * ltc.lobe_albedo() * ltc.ltc_integral()};
}

}  // namespace penumbra
