#pragma once
// `sa` for polygons: Peters' solid angle sampling (Peters 2021, Sec. 5) of a quad or polygon
// light, as a point strategy (core/strategies/strategy.h). Directions are uniform in the light's
// solid angle (including any part below the shading point's horizon, where the integrand is 0);
// the point is where the direction meets the light's plane.
//
// Measures: sample() and pdf() are per unit AREA of the light:
//   p_area = p_sa * cos(theta_light) / r^2,   p_sa = 1 / solid angle.
// The light emits on one side: a shading point behind it (or on its plane) gets no samples.
// Disks are refused (std::invalid_argument): they are not polygons.

#include <optional>

#include "core/math/vec.h"
#include "core/polygon/polygon_light.h"
#include "core/polygon/solid_angle_polygon.h"
#include "core/scene/scene.h"
#include "core/strategies/strategy.h"

namespace penumbra {

class PetersSolidAngleStrategy {
 public:
  PetersSolidAngleStrategy(const ShadingPoint& sp, const Light& light);

  static const char* name() { return "sa"; }
  std::optional<LightPoint> sample(const Vec2& u) const;
  // Area density at a point on the light; 0 outside the polygon or behind it.
  double pdf(const Vec3& light_point) const;
  double solid_angle() const { return sampler_.solid_angle(); }

 private:
  static SolidAnglePolygonSampler make_sampler(const Vec3& position,
                                               const PolygonLightGeometry& geometry);

  Vec3 position_;
  PolygonLightGeometry geometry_;
  SolidAnglePolygonSampler sampler_;
};

}  // namespace penumbra
