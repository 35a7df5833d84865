#pragma once
// What every light-sampling strategy, the estimator and the exact references share about the
// point being shaded and a point drawn on a light: the shading point (position, normal, view
// direction, material or pbrt-v3 BSDF), the BSDF as the strategies evaluate and sample it, and a
// light point with its density. Below core/strategies and the polygon geometry of core/math:
// neither is included here.

#include <optional>

#include "core/materials/bsdf.h"
#include "core/materials/surface_bsdf.h"
#include "core/math/vec.h"
#include "core/scene/scene.h"

namespace penumbra {

struct ShadingPoint {
  Vec3 position;
  Vec3 normal;  // geometric normal, flipped to face wo
  Vec3 wo;      // unit, towards the viewer
  const Material* material = nullptr;
  // The hit's BSDF for pbrt-v3 materials (textures evaluated, in the shading frame;
  // core/materials/surface_bsdf.h), owned by whoever made the shading point. Null: `material`
  // is a JSON material, evaluated about `normal`.
  const SurfaceBsdf* bsdf = nullptr;
};

// The shading point's BSDF as the estimator and the strategies use it. Directions are unit and
// point away from the surface; wi below the geometric horizon gives 0.
//   shading_bsdf:  f(wo, wi) |cos(shading normal, wi)| / cos(normal, wi), so that times the
//                  geometric cosine it is f |cos_s| (for JSON materials just f)
//   shading_bsdf_pdf / sample_shading_bsdf: the density of the BSDF's importance sampling in
//                  solid angle, and a draw from it (empty: a failed draw)
inline Rgb shading_bsdf(const ShadingPoint& sp, const Vec3& wi) {
  if (sp.bsdf) return sp.bsdf->f_for_geometric_cosine(sp.wo, wi);
  return eval_bsdf(*sp.material, sp.normal, sp.wo, wi);
}
inline double shading_bsdf_pdf(const ShadingPoint& sp, const Vec3& wi) {
  if (sp.bsdf) return sp.bsdf->pdf(sp.wo, wi);
  return pdf_bsdf(*sp.material, sp.normal, sp.wo, wi);
}
inline std::optional<BsdfSample> sample_shading_bsdf(const ShadingPoint& sp, const Vec2& u) {
  if (sp.bsdf) {
    auto s = sp.bsdf->sample(sp.wo, u);
    if (!s) return std::nullopt;
    return BsdfSample{s->wi, s->pdf};
  }
  return sample_bsdf(*sp.material, sp.normal, sp.wo, u);
}

struct LightPoint {
  Vec3 position;
  double pdf_area = 0;  // > 0 for a returned sample
};

}  // namespace penumbra
