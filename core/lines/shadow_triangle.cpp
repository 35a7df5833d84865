#include "core/lines/shadow_triangle.h"

#include <cmath>

namespace penumbra {

std::optional<ShadowTriangle> ShadowTriangle::make(const Vec3& x, const Vec3& a, const Vec3& b,
                                                   const ShadowTriangleTolerances& tolerances) {
  Vec3 to_a = a - x, to_b = b - x, segment = b - a;
  // cross(to_a, to_b) == cross(to_a, segment); the latter does not cancel when x is far away
  // (to_a and to_b nearly parallel).
  Vec3 normal = cross(to_a, segment);
  double normal_length_squared = length_squared(normal);
  // Degenerate when the angle at x is below ~1e-10 rad (a == b, x on the segment's line) or
  // when the squared lengths leave the double range.
  double scale = length_squared(to_a) * length_squared(to_b);
  // (Non-finite input fails here too: NaN and infinity make `scale` NaN or infinite.)
  if (!(normal_length_squared > 1e-20 * scale) || !std::isfinite(scale)) return std::nullopt;

  std::optional<ShadowTriangle> result(std::in_place);  // filled in place (no copy)
  ShadowTriangle& shadow = *result;
  shadow.x = x;
  shadow.to_a = to_a;
  shadow.to_b = to_b;
  // alpha(a) = 1, alpha(b) = 0 and beta(a) = 0, beta(b) = 1, both 0 along the plane normal.
  double inverse = 1 / normal_length_squared;
  shadow.alpha_gradient = cross(to_b, normal) * inverse;
  shadow.beta_gradient = cross(normal, to_a) * inverse;
  // Unnormalized: for small integer coordinates the signed distances are then exact, so
  // vertices exactly on the plane are recognised as such.
  shadow.plane_normal = normal;
  shadow.s_min = tolerances.self_occlusion_epsilon;
  shadow.s_max = 1 - tolerances.light_plane_epsilon;
  // The free zone's size near x: s_min times the distance from x to the segment's line.
  shadow.self_occlusion_distance =
      shadow.s_min * std::sqrt(normal_length_squared / length_squared(segment));
  shadow.self_occlusion_distance_squared =
      shadow.self_occlusion_distance * shadow.self_occlusion_distance;
  // Finite whenever the checks above pass; guarded anyway (one test for six values).
  double sum = dot(shadow.alpha_gradient, Vec3(1, 1, 1)) + dot(shadow.beta_gradient, Vec3(1, 1, 1));
  if (!std::isfinite(sum)) return std::nullopt;
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
  for (int k = 0; k < 3; ++k)
    for (int axis = 0; axis < 3; ++axis)
      occluder.v[k][axis] = static_cast<float>(vertices[k][axis]);
  return occluder;
}

std::optional<Interval> occluder_cut(const ShadowTriangle& shadow,
                                     const OccluderTriangle& occluder) {
  const Vec3 v[3] = {occluder.vertex(0), occluder.vertex(1), occluder.vertex(2)};
  // The shadow triangle against the occluder's plane (Möller 1997's other rejection): x on
  // the plane means edge-on; x, a, b strictly on one side means no crossing. First, since
  // the node tests have already kept mostly triangles near the shadow plane.
  Vec3 occluder_normal = cross(v[1] - v[0], v[2] - v[0]);
  double x_side = dot(occluder_normal, shadow.x - v[0]);
  if (x_side * x_side <= shadow.self_occlusion_distance_squared * length_squared(occluder_normal))
    return std::nullopt;
  double a_side = x_side + dot(occluder_normal, shadow.to_a);
  double b_side = x_side + dot(occluder_normal, shadow.to_b);
  if (x_side > 0 && a_side > 0 && b_side > 0) return std::nullopt;
  if (x_side < 0 && a_side < 0 && b_side < 0) return std::nullopt;

  // Signed distances of the vertices to the shadow plane.
  Vec3 q[3] = {v[0] - shadow.x, v[1] - shadow.x, v[2] - shadow.x};
  double distance[3];
  for (int k = 0; k < 3; ++k) distance[k] = dot(q[k], shadow.plane_normal);
  // Entirely on one side: no crossing. In the plane: coplanar, does not occlude.
  if (distance[0] > 0 && distance[1] > 0 && distance[2] > 0) return std::nullopt;
  if (distance[0] < 0 && distance[1] < 0 && distance[2] < 0) return std::nullopt;
  if (distance[0] == 0 && distance[1] == 0 && distance[2] == 0) return std::nullopt;

  double alpha[3], beta[3];
  for (int k = 0; k < 3; ++k) {
    alpha[k] = dot(q[k], shadow.alpha_gradient);
    beta[k] = dot(q[k], shadow.beta_gradient);
  }

  // Endpoints of the crossing segment, in plane coordinates: vertices on the plane, then edges
  // whose vertices lie strictly on opposite sides. With at most two vertices on the plane
  // (the coplanar case has returned), there are at most two endpoints.
  double end_alpha[2], end_beta[2];
  int end_count = 0;
  for (int k = 0; k < 3; ++k) {
    if (distance[k] == 0) {
      end_alpha[end_count] = alpha[k];
      end_beta[end_count] = beta[k];
      ++end_count;
    }
  }
  static constexpr int kEdges[3][2] = {{0, 1}, {0, 2}, {1, 2}};  // first vertex canonical-less
  for (const auto& edge : kEdges) {
    int i = edge[0], j = edge[1];
    if (!((distance[i] < 0 && distance[j] > 0) || (distance[i] > 0 && distance[j] < 0))) continue;
    if (end_count == 2) break;  // unreachable for finite input; guards the arrays
    // Crossing of edge (i, j) with the plane, from the canonical vertex order only.
    double denominator = distance[j] - distance[i];
    end_alpha[end_count] = (distance[j] * alpha[i] - distance[i] * alpha[j]) / denominator;
    end_beta[end_count] = (distance[j] * beta[i] - distance[i] * beta[j]) / denominator;
    ++end_count;
  }
  // A single touching vertex occludes a set of measure zero.
  if (end_count < 2) return std::nullopt;

  // Keep the part with depth s in [s_min, s_max]: strictly between x and the segment.
  double depth[2] = {end_alpha[0] + end_beta[0], end_alpha[1] + end_beta[1]};
  if (depth[0] <= shadow.s_min && depth[1] <= shadow.s_min) return std::nullopt;
  if (depth[0] >= shadow.s_max && depth[1] >= shadow.s_max) return std::nullopt;
  if (!(std::isfinite(depth[0]) && std::isfinite(depth[1]))) return std::nullopt;
  auto clip_endpoint = [&](int k, double bound) {
    // Move endpoint k along the crossing segment to depth `bound` (the other endpoint lies on
    // the far side of `bound`, so the denominator is nonzero).
    int other = 1 - k;
    double f = (bound - depth[k]) / (depth[other] - depth[k]);
    end_alpha[k] += f * (end_alpha[other] - end_alpha[k]);
    end_beta[k] += f * (end_beta[other] - end_beta[k]);
    depth[k] = end_alpha[k] + end_beta[k];
  };
  for (int k = 0; k < 2; ++k) {
    if (depth[k] < shadow.s_min) clip_endpoint(k, shadow.s_min);
    if (depth[k] > shadow.s_max) clip_endpoint(k, shadow.s_max);
  }
  if (!(depth[0] > 0 && depth[1] > 0)) return std::nullopt;  // rounding guard

  // Project both endpoints from x onto the segment's line: t = beta / s. The projection is
  // monotone along a segment with s > 0, so the cut is the range of the two.
  double t0 = end_beta[0] / depth[0];
  double t1 = end_beta[1] / depth[1];
  double lo = std::max(std::min(t0, t1), 0.0);
  double hi = std::min(std::max(t0, t1), 1.0);
  if (!(lo < hi)) return std::nullopt;

  return Interval{lo, hi};
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
