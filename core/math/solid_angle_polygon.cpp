#include "core/math/solid_angle_polygon.h"

#include <algorithm>
#include <cmath>

namespace penumbra {

namespace {

// det(a, b, c) for directions given by (possibly far away) points: the edge vectors b - a and
// c - a carry the triangle's size without the cancellation that det(a, b, c) would suffer when
// a, b, c are nearly parallel (a tiny, distant polygon).
double triple_product_from_edges(const Vec3& a, const Vec3& b, const Vec3& c) {
  return dot(a, cross_accurate(b - a, c - a));
}

}  // namespace

double polygon_solid_angle(std::span<const Vec3> vertices) {
  double total = 0;
  for (size_t i = 1; i + 1 < vertices.size(); ++i)
    total += triangle_solid_angle(vertices[0], vertices[i], vertices[i + 1]);
  return total;
}

PreparedSphericalTriangle prepare_spherical_triangle(const Vec3& p0, const Vec3& p1,
                                                     const Vec3& p2) {
  PreparedSphericalTriangle t;
  double l0 = length(p0), l1 = length(p1), l2 = length(p2);
  if (!(l0 > 0 && l1 > 0 && l2 > 0) || !std::isfinite(l0 * l1 * l2)) return t;
  t.v0 = p0 / l0;
  t.v1 = p1 / l1;
  t.v2 = p2 / l2;
  t.g0 = triple_product_from_edges(p0, p1, p2) / (l0 * l1 * l2);
  // Orient the triangle so that its determinant is non-negative: the subtriangle construction
  // below assumes counter-clockwise vertices as seen from outside the sphere.
  if (t.g0 < 0) {
    std::swap(t.v1, t.v2);
    t.g0 = -t.g0;
  }
  t.g1 = dot(t.v0, t.v2) + dot(t.v1, t.v2);
  t.g2 = 1.0 + dot(t.v0, t.v1);
  // Peters Eq. 13.
  t.solid_angle = 2.0 * std::atan2(t.g0, t.g2 + t.g1);
  if (!std::isfinite(t.solid_angle) || t.solid_angle < 0) t.solid_angle = 0;
  return t;
}

Vec3 sample_spherical_triangle(const PreparedSphericalTriangle& triangle, const Vec2& u) {
  const Vec3& v0 = triangle.v0;
  const Vec3& v1 = triangle.v1;
  // Subtriangle (v0, v1, v2') with solid angle A = u.x * solid_angle (Peters Sec. 5): v2' lies on
  // the arc v0 v2 and on the line with direction
  //   r = (G0 cos(A/2) - G1 sin(A/2)) v0 + G2 sin(A/2) v2,
  // and it is the second intersection of that line with the unit sphere besides -v0.
  double half_area = 0.5 * u.x * triangle.solid_angle;
  double s = std::sin(half_area), c = std::cos(half_area);
  Vec3 r = (triangle.g0 * c - triangle.g1 * s) * v0 + (triangle.g2 * s) * triangle.v2;
  double r_length = length(r);
  Vec3 v2_sub = v0;
  if (r_length > 0 && std::isfinite(r_length)) {
    Vec3 r_unit = r / r_length;
    v2_sub = 2.0 * dot(v0, r_unit) * r_unit - v0;
    double l = length(v2_sub);
    v2_sub = l > 0 ? v2_sub / l : v0;
  }
  // Direction on the arc from v1 to v2' with 1 - cos(angle to v1) uniform in
  // [0, 1 - v1.v2'] (Arvo 1995). 1 - v1.v2' is formed as |v2' - v1|^2 / 2, which keeps its
  // relative accuracy for short arcs.
  Vec3 chord = v2_sub - v1;
  double one_minus_cos_max = std::min(2.0, 0.5 * length_squared(chord));
  double h = u.y * one_minus_cos_max;                   // 1 - cos(theta) of the sample
  Vec3 perpendicular = chord + v1 * one_minus_cos_max;  // v2' - (v1.v2') v1
  double perpendicular_length = length(perpendicular);
  if (!(perpendicular_length > 0)) return v1;
  double sin_theta = safe_sqrt(h * (2.0 - h));
  Vec3 direction = v1 * (1.0 - h) + perpendicular * (sin_theta / perpendicular_length);
  return normalize(direction);
}

SolidAnglePolygonSampler::SolidAnglePolygonSampler(std::span<const Vec3> vertices) {
  int n = static_cast<int>(vertices.size());
  if (n < 3 || n > kMaxPolygonVertices) return;
  // Triangle fan around vertex 0 (Peters Fig. 11a); degenerate triangles are dropped.
  for (int i = 1; i + 1 < n; ++i) {
    PreparedSphericalTriangle t =
        prepare_spherical_triangle(vertices[0], vertices[i], vertices[i + 1]);
    if (t.solid_angle > 0) {
      triangles_[triangle_count_++] = t;
      solid_angle_ += t.solid_angle;
    }
  }
  if (!(solid_angle_ > 0) || !std::isfinite(solid_angle_)) {
    solid_angle_ = 0;
    triangle_count_ = 0;
  }
}

std::optional<Vec3> SolidAnglePolygonSampler::sample(const Vec2& u) const {
  if (triangle_count_ == 0) return std::nullopt;
  // Choose a fan triangle in proportion to its solid angle and reuse u.x inside it.
  double target = u.x * solid_angle_;
  int chosen = triangle_count_ - 1;
  double before = 0;
  for (int i = 0; i < triangle_count_; ++i) {
    if (target < before + triangles_[i].solid_angle || i == triangle_count_ - 1) {
      chosen = i;
      break;
    }
    before += triangles_[i].solid_angle;
  }
  const PreparedSphericalTriangle& t = triangles_[chosen];
  double local = std::clamp((target - before) / t.solid_angle, 0.0, 1.0);
  Vec3 direction = sample_spherical_triangle(t, {local, u.y});
  if (!is_finite(direction)) return std::nullopt;
  return direction;
}

}  // namespace penumbra
