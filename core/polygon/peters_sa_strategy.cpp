#include "core/polygon/peters_sa_strategy.h"

#include <cmath>

namespace penumbra {

SolidAnglePolygonSampler PetersSolidAngleStrategy::make_sampler(
    const Vec3& position, const PolygonLightGeometry& geometry) {
  if (!geometry.emits_towards(position)) return SolidAnglePolygonSampler({});
  std::array<Vec3, kMaxPolygonVertices> relative;
  for (int i = 0; i < geometry.vertex_count; ++i) relative[i] = geometry.vertices[i] - position;
  return SolidAnglePolygonSampler({relative.data(), size_t(geometry.vertex_count)});
}

PetersSolidAngleStrategy::PetersSolidAngleStrategy(const ShadingPoint& sp, const Light& light)
    : position_(sp.position),
      geometry_(polygon_light_geometry(light)),
      sampler_(make_sampler(position_, geometry_)) {}

std::optional<LightPoint> PetersSolidAngleStrategy::sample(const Vec2& u) const {
  std::optional<Vec3> direction = sampler_.sample(u);
  if (!direction) return std::nullopt;
  double distance = 0;
  std::optional<Vec3> point = geometry_.plane_hit(position_, *direction, &distance);
  if (!point) return std::nullopt;
  // Solid angle density to area density: p_sa cos(theta_light) / r^2.
  double cos_light = -dot(geometry_.normal, *direction);
  double pdf_area = sampler_.pdf() * cos_light / (distance * distance);
  if (!(pdf_area > 0) || !std::isfinite(pdf_area)) return std::nullopt;
  return LightPoint{*point, pdf_area};
}

double PetersSolidAngleStrategy::pdf(const Vec3& light_point) const {
  if (!(sampler_.solid_angle() > 0)) return 0.0;
  Vec3 to_light = light_point - position_;
  double r2 = length_squared(to_light);
  if (!(r2 > 0)) return 0.0;
  double cos_light = -dot(geometry_.normal, to_light) / std::sqrt(r2);
  if (!(cos_light > 0) || !geometry_.contains(light_point)) return 0.0;
  double pdf_area = sampler_.pdf() * cos_light / r2;
  return std::isfinite(pdf_area) ? pdf_area : 0.0;
}

}  // namespace penumbra
