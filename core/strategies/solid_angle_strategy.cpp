#include "core/strategies/solid_angle_strategy.h"

#include "core/lights/light_geometry.h"
#include "core/math/solid_angle_polygon.h"
#include "core/math/spherical_triangle.h"

namespace penumbra {
namespace {

// Quads whose edges are perpendicular to 1e-6 relative are rectangles (SCENE_FORMAT.md).
bool is_rectangle(const Light& light) {
  return std::abs(dot(light.edge1, light.edge2)) <=
         1e-6 * length(light.edge1) * length(light.edge2);
}

}  // namespace

SolidAngleStrategy::SolidAngleStrategy(const ShadingPoint& sp, const Light& light)
    : light_(&light), x_(sp.position) {
  if (!is_finite(x_) || !light_faces_point(light, x_)) return;
  if (light.type == LightType::Quad && is_rectangle(light)) {
    // Ureña et al. 2013: the spherical rectangle.
    auto rectangle = SphericalRectangle::prepare(x_, light.origin, light.edge1, light.edge2);
    if (!rectangle) return;
    rectangle_ = *rectangle;
    solid_angle_ = rectangle_.solid_angle;
    domain_ = Domain::Rectangle;
  } else if (light.type == LightType::Disk) {
    // The cone bounding the disk: tangent to its bounding sphere, or the hemisphere towards the
    // light when x is within the radius of the centre.
    Vec3 to_center = light.center - x_;
    double distance = length(to_center);
    double sin_max = distance > 0 ? light.radius / distance : 2.0;
    if (sin_max < 1.0) {
      cone_frame_ = Frame::from_normal(to_center / distance);
      double sin_sq = sin_max * sin_max;
      cone_one_minus_cos_ = sin_sq / (1.0 + std::sqrt((1.0 - sin_max) * (1.0 + sin_max)));
    } else {
      cone_frame_ = Frame::from_normal(-light.normal);
      cone_one_minus_cos_ = 1.0;
    }
    solid_angle_ = 2.0 * kPi * cone_one_minus_cos_;
    domain_ = Domain::Cone;
  } else if (light.vertices.size() >= 3 && light.vertices.size() <= size_t(kMaxPolygonVertices)) {
    // Quads that are not rectangles, and polygons: Peters' triangle fan.
    std::array<Vec3, kMaxPolygonVertices> relative;
    for (size_t i = 0; i < light.vertices.size(); ++i) relative[i] = light.vertices[i] - x_;
    fan_.emplace(std::span<const Vec3>(relative.data(), light.vertices.size()));
    solid_angle_ = fan_->solid_angle();
    domain_ = Domain::Fan;
  } else if (light.vertices.size() >= 3) {
    // More vertices than the polygon samplers' fixed arrays hold.
    for (size_t i = 0; i + 2 < light.vertices.size(); ++i) solid_angle_ += large_fan_triangle(i);
    domain_ = Domain::LargeFan;
  }
  if (!(solid_angle_ > 0) || !std::isfinite(solid_angle_)) {
    domain_ = Domain::None;
    solid_angle_ = 0;
  }
}

std::optional<LightPoint> SolidAngleStrategy::sample(const Vec2& u_in) const {
  Vec2 u{std::clamp(u_in.x, 0.0, 1.0), std::clamp(u_in.y, 0.0, 1.0)};
  switch (domain_) {
    case Domain::None:
      return std::nullopt;
    case Domain::Rectangle:
      return finish(rectangle_.sample(u));
    case Domain::Fan: {
      std::optional<Vec3> direction = fan_->sample(u);
      return direction ? along(*direction) : std::nullopt;
    }
    case Domain::LargeFan:
      return sample_large_fan(u);
    case Domain::Cone:
      return sample_cone(u);
  }
  return std::nullopt;
}

double SolidAngleStrategy::large_fan_triangle(size_t i) const {
  const std::vector<Vec3>& v = light_->vertices;
  return triangle_solid_angle(v[0] - x_, v[i + 1] - x_, v[i + 2] - x_);
}

std::optional<LightPoint> SolidAngleStrategy::sample_large_fan(const Vec2& u) const {
  // A fan triangle chosen by its solid angle, u.x reused inside it (as SolidAnglePolygonSampler).
  const std::vector<Vec3>& v = light_->vertices;
  double target = u.x * solid_angle_, before = 0, chosen_begin = 0, chosen_omega = 0;
  size_t chosen = 0;
  for (size_t i = 0; i + 2 < v.size(); ++i) {
    double omega = large_fan_triangle(i);
    if (!(omega > 0)) continue;
    chosen = i;
    chosen_omega = omega;
    chosen_begin = before;
    if (target < before + omega) break;
    before += omega;
  }
  if (!(chosen_omega > 0)) return std::nullopt;
  PreparedSphericalTriangle triangle =
      prepare_spherical_triangle(v[0] - x_, v[chosen + 1] - x_, v[chosen + 2] - x_);
  if (!(triangle.solid_angle > 0)) return std::nullopt;
  double local = std::clamp((target - chosen_begin) / chosen_omega, 0.0, 1.0);
  return along(sample_spherical_triangle(triangle, {local, u.y}));
}

std::optional<LightPoint> SolidAngleStrategy::along(const Vec3& direction) const {
  double distance = light_plane_height(*light_, x_) / -dot(light_->normal, direction);
  if (!(distance > 0) || !std::isfinite(distance)) return std::nullopt;
  return finish(x_ + distance * direction);
}

std::optional<LightPoint> SolidAngleStrategy::sample_cone(const Vec2& u) const {
  double one_minus_cos = u.x * cone_one_minus_cos_;
  double cos_theta = 1.0 - one_minus_cos;
  double sin_theta = safe_sqrt(one_minus_cos * (2.0 - one_minus_cos));
  double phi = 2.0 * kPi * u.y;
  Vec3 direction =
      cone_frame_.to_world({sin_theta * std::cos(phi), sin_theta * std::sin(phi), cos_theta});
  double denominator = dot(light_->normal, direction);
  double distance = light_plane_height(*light_, x_) / -denominator;
  if (!(distance > 0) || !std::isfinite(distance)) return std::nullopt;
  Vec3 point = x_ + distance * direction;
  // A direction of the cone that misses the disk: no sample.
  if (!(length_squared(point - light_->center) <= light_->radius * light_->radius))
    return std::nullopt;
  return finish(point);
}

std::optional<LightPoint> SolidAngleStrategy::finish(const Vec3& point) const {
  if (!is_finite(point)) return std::nullopt;
  double pdf_area = pdf(point);
  if (!(pdf_area > 0)) return std::nullopt;
  return LightPoint{point, pdf_area};
}

double SolidAngleStrategy::pdf(const Vec3& light_point) const {
  if (domain_ == Domain::None) return 0;
  // p_area = p_sa cos(theta_light) / r^2 with p_sa = 1 / Omega.
  Vec3 d = light_point - x_;
  double r_squared = length_squared(d);
  if (!(r_squared > 0)) return 0;
  double pdf_area =
      std::abs(dot(light_->normal, d)) / (r_squared * std::sqrt(r_squared) * solid_angle_);
  return std::isfinite(pdf_area) ? pdf_area : 0.0;
}

}  // namespace penumbra
