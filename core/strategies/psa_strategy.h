#pragma once
// `psa`: projected solid angle sampling of a quad or polygon light (Peters 2021, Sec. 3), as a
// point strategy (core/strategies/strategy.h). Directions are drawn with density
// cos(theta_x) / projected solid angle (per unit solid angle) over the part of the light above
// the shading point's horizon; the point is where the direction meets the light's plane.
//
// Parameters: `iterations` of the tangent-line iteration (default
// ProjectedSolidAngleSampler::kDefaultIterations).
// Measures: sample() and pdf() are per unit AREA of the light:
//   p_area = p_psa * cos(theta_x) * cos(theta_light) / r^2,   p_psa = 1 / projected solid angle.
// The light emits on one side: a shading point behind it (or on its plane) gets no samples.
// Disks are refused (std::invalid_argument): they are not polygons.

#include <optional>
#include <string>
#include <string_view>

#include "core/lights/polygon_light.h"
#include "core/math/projected_solid_angle.h"
#include "core/math/vec.h"
#include "core/scene/scene.h"
#include "core/strategies/light_checks.h"
#include "core/strategies/registry.h"
#include "core/strategies/strategy.h"

namespace penumbra {

class ProjectedSolidAngleStrategy {
 public:
  ProjectedSolidAngleStrategy(const ShadingPoint& sp, const Light& light,
                              int iterations = ProjectedSolidAngleSampler::kDefaultIterations);

  static constexpr std::string_view name() { return "psa"; }
  static constexpr StrategyFamily kFamily = StrategyFamily::Point;
  static constexpr bool kRectangleStrata = false;
  // Quads and convex polygons of up to kMaxPolygonVertices vertices (not disks).
  static std::optional<std::string> refusal(const Scene& scene, LineDirection) {
    return polygon_lights_only(name(), scene);
  }
  // Empty: no light above the horizon on the emitting side, or a degenerate direction.
  std::optional<LightPoint> sample(const Vec2& u) const;
  // Area density at a point on the light; 0 outside the polygon, below the horizon or behind.
  double pdf(const Vec3& light_point) const;
  // The light's projected solid angle seen from the shading point (closed form).
  double projected_solid_angle() const { return sampler_.projected_solid_angle(); }

 private:
  static ProjectedSolidAngleSampler make_sampler(const Vec3& position, const Frame& frame,
                                                 const PolygonLightGeometry& geometry,
                                                 int iterations);

  Vec3 position_;
  Frame frame_;
  PolygonLightGeometry geometry_;
  ProjectedSolidAngleSampler sampler_;
};

}  // namespace penumbra
