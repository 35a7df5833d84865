#pragma once
// Point strategies: each draws a point on a light for a shading point and returns its density
// in AREA measure on the light, and evaluates that density for any point on the light (for MIS).
// A strategy is prepared once per (shading point, light) and then sampled N times, so per-point
// set-up (Ureña's spherical rectangle, a polygon's fan of solid angles) is paid once.
//
// Measures: every pdf returned here is per unit area of the light. A solid-angle density p_sa
// converts as p_area = p_sa * |cos theta_light| / r^2.

#include <optional>

#include "core/math/vec.h"
#include "core/scene/scene.h"

namespace penumbra {

struct ShadingPoint {
  Vec3 position;
  Vec3 normal;  // geometric normal, flipped to face wo
  Vec3 wo;      // unit, towards the viewer
  const Material* material = nullptr;
};

struct LightPoint {
  Vec3 position;
  double pdf_area = 0;  // > 0 for a returned sample
};

// Every point strategy has this shape (one header and one .cpp each, in core/strategies/):
//
//   class XStrategy {
//    public:
//     XStrategy(const ShadingPoint& sp, const Light& light);   // per-point set-up
//     std::optional<LightPoint> sample(const Vec2& u) const;    // empty: no sample (miss, degenerate)
//     double pdf(const Vec3& light_point) const;                // area density, 0 where it cannot draw
//   };
//
// AreaStrategy (area_strategy.h), SolidAngleStrategy (solid_angle_strategy.h),
// BsdfStrategy (bsdf_strategy.h). Later: projected solid angle and LTC (Peters 2021).

}  // namespace penumbra
