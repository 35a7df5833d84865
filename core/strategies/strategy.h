#pragma once
// Point strategies: each draws a point on a light for a shading point and returns its density
// in AREA measure on the light, and evaluates that density for any point on the light (for MIS).
// A strategy is prepared once per (shading point, light) and then sampled N times, so per-point
// set-up (Ureña's spherical rectangle, a polygon's fan of solid angles) is paid once.
//
// Measures: every pdf returned here is per unit area of the light. A solid-angle density p_sa
// converts as p_area = p_sa * |cos theta_light| / r^2.

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

// The shape of each family of strategies (core/strategies/registry.h; every strategy is one
// header and one .cpp in core/strategies/ and one row of registered_strategies.h):
//
//   Point (bsdf, area, sa, psa, ltc):
//     XStrategy(const ShadingPoint& sp, const Light& light);   // per-point set-up
//     std::optional<LightPoint> sample(const Vec2& u) const;    // empty: no sample
//     double pdf(const Vec3& light_point) const;                // area density, 0 where it
//                                                               // cannot draw
//   Line (line-area, line-sa): the same with a line family and the scene's line query,
//     XStrategy(sp, light, LineAxis axis, const LineQuery& query);
//     std::optional<LightPoint> sample(const Vec2& u, TracedLine& line, double& t) const;
//     double pdf(const TracedLine& line, double t, const Vec3& light_point) const;
//   AnalyticLine (line-bd16): whole lines in closed form, no density at a point,
//     XStrategy(sp, light, LineDirection direction);
//     Rgb estimate_sum(Pattern, const StreamKey&, int n, const LineQuery&) const;

}  // namespace penumbra
