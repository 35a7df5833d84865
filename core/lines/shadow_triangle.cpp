#include "core/lines/shadow_triangle.h"

#include <cmath>

namespace penumbra {

std::optional<ShadowTriangle> ShadowTriangle::make(const Vec3& x, const Vec3& a, const Vec3& b,
                                                   const ShadowTriangleTolerances& tolerances) {
  std::optional<ShadowTriangle> result(std::in_place);
  if (!result->set(x, a, b, tolerances)) result.reset();
  return result;
}

bool is_occluder_triangle(const Vec3& v0, const Vec3& v1, const Vec3& v2) {
  if (!is_finite(v0) || !is_finite(v1) || !is_finite(v2)) return false;
  Vec3 area_vector = cross(v1 - v0, v2 - v0);
  return area_vector.x != 0 || area_vector.y != 0 || area_vector.z != 0;
}

std::optional<OccluderTriangle> OccluderTriangle::make(const Vec3& v0, const Vec3& v1,
                                                       const Vec3& v2) {
  auto round_to_float = [](const Vec3& p) {
    return Vec3(static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z));
  };
  Vec3 vertices[3] = {round_to_float(v0), round_to_float(v1), round_to_float(v2)};
  if (!is_occluder_triangle(vertices[0], vertices[1], vertices[2])) return std::nullopt;
  order_canonically(vertices[0], vertices[1], vertices[2]);
  OccluderTriangle occluder;
  for (int axis = 0; axis < 3; ++axis) {
    for (int k = 0; k < 3; ++k)
      occluder.coordinate[axis][k] = static_cast<float>(vertices[k][axis]);
    occluder.coordinate[axis][3] = 0;
  }
  return occluder;
}

bool segment_hits_triangle(const Vec3& x, const Vec3& p, double s_min, double s_max, const Vec3& v0,
                           const Vec3& v1, const Vec3& v2) {
  // Möller & Trumbore 1997, with the ray x + s (p - x).
  Vec3 direction = p - x;
  Vec3 edge1 = v1 - v0, edge2 = v2 - v0;
  Vec3 p_vector = cross(direction, edge2);
  double determinant = dot(edge1, p_vector);
  if (determinant == 0 || !std::isfinite(determinant)) return false;
  double inverse_determinant = 1 / determinant;
  Vec3 t_vector = x - v0;
  double u = dot(t_vector, p_vector) * inverse_determinant;
  if (u < 0 || u > 1) return false;
  Vec3 q_vector = cross(t_vector, edge1);
  double v = dot(direction, q_vector) * inverse_determinant;
  if (v < 0 || u + v > 1) return false;
  double s = dot(edge2, q_vector) * inverse_determinant;
  return s > s_min && s < s_max;
}

void visible_intervals_brute_force(const std::vector<Vec3>& positions,
                                   const std::vector<uint32_t>& indices, const Vec3& x,
                                   const Vec3& a, const Vec3& b, IntervalList& out,
                                   const ShadowTriangleTolerances& tolerances) {
  out.reset();
  if (!is_finite(x) || !is_finite(a) || !is_finite(b)) {
    out.clear();
    return;
  }
  std::optional<ShadowTriangle> shadow = ShadowTriangle::make(x, a, b, tolerances);
  size_t triangle_count = indices.size() / 3;
  if (!shadow) {
    // Degenerate shadow triangle: one shadow ray to the segment's midpoint.
    Vec3 midpoint = 0.5 * (a + b);
    for (size_t i = 0; i < triangle_count; ++i) {
      std::optional<OccluderTriangle> occluder = OccluderTriangle::make(
          positions[indices[3 * i]], positions[indices[3 * i + 1]], positions[indices[3 * i + 2]]);
      if (!occluder) continue;
      if (segment_hits_triangle(x, midpoint, tolerances.self_occlusion_epsilon,
                                1 - tolerances.light_plane_epsilon, occluder->vertex(0),
                                occluder->vertex(1), occluder->vertex(2))) {
        out.clear();
        return;
      }
    }
    return;
  }
  for (size_t i = 0; i < triangle_count; ++i) {
    std::optional<OccluderTriangle> occluder = OccluderTriangle::make(
        positions[indices[3 * i]], positions[indices[3 * i + 1]], positions[indices[3 * i + 2]]);
    if (!occluder) continue;
    if (std::optional<Interval> cut = occluder_cut(*shadow, *occluder)) {
      out.subtract(cut->lo, cut->hi);
      if (out.fully_occluded()) return;
    }
  }
}

}  // namespace penumbra
