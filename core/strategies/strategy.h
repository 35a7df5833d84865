#pragma once
// Point strategies: each draws a point on a light for a shading point and returns its density
// in AREA measure on the light, and evaluates that density for any point on the light (for MIS).
// A strategy is prepared once per (shading point, light) and then sampled N times, so per-point
// set-up (Ureña's spherical rectangle, a polygon's fan of solid angles) is paid once.
//
// Measures: every pdf returned here is per unit area of the light. A solid-angle density p_sa
// converts as p_area = p_sa * |cos theta_light| / r^2.

#include "core/lights/shading_point.h"  // ShadingPoint, LightPoint

namespace penumbra {

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
