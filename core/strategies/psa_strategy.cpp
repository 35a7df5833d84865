#include "core/strategies/psa_strategy.h"

#include <cmath>

namespace penumbra {

ProjectedSolidAngleSampler ProjectedSolidAngleStrategy::make_sampler(
    const Vec3& position, const Frame& frame, const PolygonLightGeometry& geometry,
    int iterations) {
  if (!geometry.emits_towards(position)) return ProjectedSolidAngleSampler({}, iterations);
  // Vertices relative to the shading point, in its local frame (z = normal), as Sec. 3.1 wants.
  std::array<Vec3, kMaxPolygonVertices> local;
  for (int i = 0; i < geometry.vertex_count; ++i)
    local[i] = frame.to_local(geometry.vertices[i] - position);
  return ProjectedSolidAngleSampler({local.data(), size_t(geometry.vertex_count)}, iterations);
}

ProjectedSolidAngleStrategy::ProjectedSolidAngleStrategy(const ShadingPoint& sp, const Light& light,
                                                         int iterations)
    : position_(sp.position),
      frame_(Frame::from_normal(normalize(sp.normal))),
      geometry_(polygon_light_geometry(light)),
      sampler_(make_sampler(position_, frame_, geometry_, iterations)) {}

std::optional<LightPoint> ProjectedSolidAngleStrategy::sample(const Vec2& u) const {
  std::optional<Vec3> local = sampler_.sample(u);
  if (!local) return std::nullopt;
  Vec3 direction = frame_.to_world(*local);
  double distance = 0;
  std::optional<Vec3> point = geometry_.plane_hit(position_, direction, &distance);
  if (!point) return std::nullopt;
  // Projected solid angle density to area density: p_psa cos(theta_x) cos(theta_light) / r^2.
  double cos_x = local->z;
  double cos_light = -dot(geometry_.normal, direction);
  double pdf_area = sampler_.pdf() * cos_x * cos_light / (distance * distance);
  if (!(pdf_area > 0) || !std::isfinite(pdf_area)) return std::nullopt;
  return LightPoint{*point, pdf_area};
}

double ProjectedSolidAngleStrategy::pdf(const Vec3& light_point) const {
  if (!(sampler_.projected_solid_angle() > 0)) return 0.0;
  Vec3 to_light = light_point - position_;
  double r2 = length_squared(to_light);
  if (!(r2 > 0)) return 0.0;
  Vec3 direction = to_light / std::sqrt(r2);
  double cos_x = dot(frame_.n, direction);
  double cos_light = -dot(geometry_.normal, direction);
  if (!(cos_x > 0) || !(cos_light > 0) || !geometry_.contains(light_point)) return 0.0;
  double pdf_area = sampler_.pdf() * cos_x * cos_light / r2;
  return std::isfinite(pdf_area) ? pdf_area : 0.0;
}

}  // namespace penumbra
