#include "core/strategies/area_strategy.h"

#include "core/lights/light_geometry.h"

namespace penumbra {

AreaStrategy::AreaStrategy(const ShadingPoint& sp, const Light& light) : light_(&light) {
  if (light.area > 0 && std::isfinite(light.area) && light_faces_point(light, sp.position))
    pdf_area_ = 1.0 / light.area;
}

std::optional<LightPoint> AreaStrategy::sample(const Vec2& u) const {
  if (!(pdf_area_ > 0)) return std::nullopt;
  Vec2 clamped{std::clamp(u.x, 0.0, 1.0), std::clamp(u.y, 0.0, 1.0)};
  Vec3 point = light_point_uniform(*light_, clamped);
  if (!is_finite(point)) return std::nullopt;
  return LightPoint{point, pdf_area_};
}

double AreaStrategy::pdf(const Vec3& /*light_point*/) const {
  return pdf_area_;
}

}  // namespace penumbra
