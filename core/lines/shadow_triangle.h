#pragma once
// The exact geometry of a line sample's visibility (Billen & Dutré 2016 Sec. 5.2): the shadow
// triangle (x, a, b) spanned by a shading point x and a segment a->b on a light, and the cut an
// occluder triangle makes in the segment's parameter t in [0,1].
//
// Coordinates. Every point p is described relative to the shadow triangle by three linear
// functions of q = p - x:
//   alpha(p) = dot(q, alpha_gradient), beta(p) = dot(q, beta_gradient)  (in-plane coordinates:
//     p = x + alpha (a - x) + beta (b - x) + off-plane part),
//   distance(p) = dot(q, plane_normal)  (signed distance to the shadow plane, times |normal|).
// On the plane, depth s = alpha + beta is 0 at x and 1 on the segment's line, and a point with
// s > 0 projects from x onto the segment at t = beta / s. An occluder triangle crosses the plane
// in a segment; the part of that segment with s in (s_min, s_max) projects to the cut.
//
// Watertightness. A closed mesh must not leak light through its seams, so two triangles that
// share an edge must produce cuts that touch exactly. The three functions above are evaluated
// per vertex (same vertex, same bits), and an edge's crossing with the plane is computed from
// its two vertices in a canonical order (lexicographic by coordinates, see canonical_less), so
// every triangle holding that edge gets the same crossing bit for bit. IntervalList then treats
// touching cuts as closed. All of this is double precision.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include "core/lines/intervals.h"
#include "core/lines/lanes.h"
#include "core/math/vec.h"

namespace penumbra {

// Tolerances of the shadow-triangle query, as fractions of the way from x (s = 0) to the
// segment (s = 1); being fractions they do not depend on the scene's scale.
struct ShadowTriangleTolerances {
  // The part of the shadow triangle with s <= self_occlusion_epsilon is free, like a shadow
  // ray's t_min: the surface x lies on (and float noise in x) does not occlude.
  double self_occlusion_epsilon = 1e-5;
  // Occluders at s >= 1 - light_plane_epsilon do not count: geometry exactly in the light's
  // plane, beyond or around the segment (a ceiling the light is set in), does not occlude it.
  double light_plane_epsilon = 1e-7;
};

struct ShadowTriangle {
  Vec3 x, to_a, to_b;                                // the shading point; a - x and b - x
  Vec3 alpha_gradient, beta_gradient, plane_normal;  // see the file comment
  double s_min = 0, s_max = 1;
  // The square of s_min as a distance: s_min times the distance from x to the segment's line.
  // An occluder whose plane passes this close to x is seen edge-on (the surface x lies on, or
  // coplanar with it) and does not occlude.
  double self_occlusion_distance_squared = 0;

  // The shadow triangle of x and segment a->b, or empty when it is degenerate (a == b, x on the
  // segment's line or too close to it for the plane to be defined, non-finite input).
  static std::optional<ShadowTriangle> make(const Vec3& x, const Vec3& a, const Vec3& b,
                                            const ShadowTriangleTolerances& tolerances = {});
  // The same in place (the line query's hot path; inline, defined below): false, with *this
  // unspecified, when degenerate.
  bool set(const Vec3& x, const Vec3& a, const Vec3& b, const ShadowTriangleTolerances& tolerances);
};

// Strict total order on points (lexicographic on x, y, z): the canonical vertex order that
// makes shared edges produce identical crossings.
inline bool canonical_less(const Vec3& p, const Vec3& q) {
  if (p.x != q.x) return p.x < q.x;
  if (p.y != q.y) return p.y < q.y;
  return p.z < q.z;
}

// Sorts a triangle's vertices into canonical order (the winding is irrelevant here).
inline void order_canonically(Vec3& v0, Vec3& v1, Vec3& v2) {
  if (canonical_less(v1, v0)) std::swap(v0, v1);
  if (canonical_less(v2, v1)) std::swap(v1, v2);
  if (canonical_less(v1, v0)) std::swap(v0, v1);
}

// A triangle that can occlude: finite coordinates and nonzero area. Zero-area triangles are
// dropped before any query (they occlude a set of measure zero).
bool is_occluder_triangle(const Vec3& v0, const Vec3& v1, const Vec3& v2);

// An occluder triangle prepared for queries: vertices rounded to float, as Embree sees them
// (large scenes are bound by memory traffic), in canonical order, stored by axis so that the
// three vertices' coordinates along an axis load as one 4-lane vector (lane 3 is padding, 0).
// Everything computed from them is double precision; the rounding is per vertex, so shared
// vertices stay shared and closed meshes stay closed.
struct alignas(16) OccluderTriangle {
  float coordinate[3][4];  // [axis][vertex], vertex 3 unused

  Vec3 vertex(int k) const { return {coordinate[0][k], coordinate[1][k], coordinate[2][k]}; }
  // Empty for triangles that cannot occlude: non-finite or zero area after rounding.
  static std::optional<OccluderTriangle> make(const Vec3& v0, const Vec3& v1, const Vec3& v2);
};

// The closed interval of t an occluder triangle removes from the segment, or empty when it
// does not cross the shadow triangle strictly between x and the segment.
// - Occluders whose plane passes through x (within the square root of
//   ShadowTriangle::self_occlusion_distance_squared) are seen edge-on and do not occlude: the
//   surface x lies on and its coplanar neighbours (rounding would otherwise give them sliver
//   cuts, false visibility boundaries).
// - Coplanar occluders (lying in the shadow plane) do not occlude: such configurations have
//   measure zero, and in a closed mesh their neighbours still cut along the shared edges.
// - Zero-length cuts are reported empty.
// Inline (defined below): the line query's traversal is compiled for SSE2 and for AVX and
// inlines it into both; the result is the same bits either way.
inline std::optional<Interval> occluder_cut(const ShadowTriangle& shadow,
                                            const OccluderTriangle& occluder);

// True when the triangle blocks the segment x->p strictly inside its parameter range
// (s_min, s_max) along x + s (p - x). Double-precision Möller-Trumbore; used for degenerate
// shadow triangles, where a line query reduces to a ray.
bool segment_hits_triangle(const Vec3& x, const Vec3& p, double s_min, double s_max, const Vec3& v0,
                           const Vec3& v1, const Vec3& v2);

// Reference line query: clips every triangle exactly, no acceleration structure. Same answer
// as LineQuery::visible_intervals (tests compare them). Degenerate shadow triangles are
// answered by one shadow ray from x to the segment's midpoint: [0,1] visible or nothing.
void visible_intervals_brute_force(const std::vector<Vec3>& positions,
                                   const std::vector<uint32_t>& indices, const Vec3& x,
                                   const Vec3& a, const Vec3& b, IntervalList& out,
                                   const ShadowTriangleTolerances& tolerances = {});

// ---------------------------------------------------------------------------------------------

inline bool ShadowTriangle::set(const Vec3& x_in, const Vec3& a, const Vec3& b,
                                const ShadowTriangleTolerances& tolerances) {
  // Everything in locals first, the members written once at the end (the inputs may alias
  // them, so writing members early would make the compiler read them back from memory).
  const Vec3 origin = x_in;
  const Vec3 segment = b - a;
  const Vec3 towards_a = a - origin, towards_b = b - origin;
  // cross(to_a, to_b) == cross(to_a, segment); the latter does not cancel when x is far away
  // (to_a and to_b nearly parallel).
  const Vec3 normal = cross(towards_a, segment);
  const double normal_length_squared = length_squared(normal);
  // Degenerate when the angle at x is below ~1e-10 rad (a == b, x on the segment's line) or
  // when the squared lengths leave the double range.
  const double scale = length_squared(towards_a) * length_squared(towards_b);
  // (Non-finite input fails here too: NaN and infinity make `scale` NaN or infinite.)
  if (!(normal_length_squared > 1e-20 * scale) || !std::isfinite(scale)) return false;

  // alpha(a) = 1, alpha(b) = 0 and beta(a) = 0, beta(b) = 1, both 0 along the plane normal.
  const double inverse = 1 / normal_length_squared;
  const Vec3 alpha = cross(towards_b, normal) * inverse;
  const Vec3 beta = cross(normal, towards_a) * inverse;
  const double near = tolerances.self_occlusion_epsilon;
  x = origin;
  to_a = towards_a;
  to_b = towards_b;
  alpha_gradient = alpha;
  beta_gradient = beta;
  // Unnormalized: for small integer coordinates the signed distances are then exact, so
  // vertices exactly on the plane are recognised as such.
  plane_normal = normal;
  s_min = near;
  s_max = 1 - tolerances.light_plane_epsilon;
  // The free zone's size near x, squared: s_min times the distance from x to the segment's line.
  self_occlusion_distance_squared = near * near * (normal_length_squared / length_squared(segment));
  // Finite whenever the checks above pass; guarded anyway (one test for six values).
  return std::isfinite(dot(alpha, Vec3(1, 1, 1)) + dot(beta, Vec3(1, 1, 1)));
}

inline std::optional<Interval> occluder_cut(const ShadowTriangle& shadow,
                                            const OccluderTriangle& occluder) {
  // Rejections, cheapest first:
  // - the occluder against the shadow plane (three signed distances, one 4-wide evaluation):
  //   entirely on one side, no crossing; in the plane, coplanar, does not occlude. Most
  //   triangles a node test lets through and that do not cut fail here;
  // - the shadow triangle against the occluder's plane (Möller 1997's other rejection): x on
  //   the plane means edge-on; x, a, b strictly on one side means no crossing. Decided together
  //   (bitwise: one hard-to-predict branch instead of one per test).
  using lanes::D2;
  using lanes::D4;
  const D4 qx = lanes::widen(occluder.coordinate[0]) - shadow.x.x;
  const D4 qy = lanes::widen(occluder.coordinate[1]) - shadow.x.y;
  const D4 qz = lanes::widen(occluder.coordinate[2]) - shadow.x.z;
  const Vec3& n = shadow.plane_normal;
  const D4 distance = qx * n.x + qy * n.y + qz * n.z;
  const double d[3] = {distance[0], distance[1], distance[2]};
  const bool occluder_on_one_side = ((d[0] > 0) & (d[1] > 0) & (d[2] > 0)) |
                                    ((d[0] < 0) & (d[1] < 0) & (d[2] < 0)) |
                                    ((d[0] == 0) & (d[1] == 0) & (d[2] == 0));
  if (occluder_on_one_side) return std::nullopt;

  const Vec3 v0 = occluder.vertex(0), v1 = occluder.vertex(1), v2 = occluder.vertex(2);
  const Vec3 occluder_normal = cross(v1 - v0, v2 - v0);
  const double x_side = dot(occluder_normal, shadow.x - v0);
  const double a_side = x_side + dot(occluder_normal, shadow.to_a);
  const double b_side = x_side + dot(occluder_normal, shadow.to_b);
  const bool edge_on =
      x_side * x_side <= shadow.self_occlusion_distance_squared * length_squared(occluder_normal);
  const bool shadow_on_one_side =
      ((x_side > 0) & (a_side > 0) & (b_side > 0)) | ((x_side < 0) & (a_side < 0) & (b_side < 0));
  if (edge_on | shadow_on_one_side) return std::nullopt;

  // The vertices' in-plane coordinates alpha and beta, all three at once: per lane the same
  // operations as dot(v - x, gradient).
  const Vec3& ga = shadow.alpha_gradient;
  const Vec3& gb = shadow.beta_gradient;
  const D4 alpha = qx * ga.x + qy * ga.y + qz * ga.z;
  const D4 beta = qx * gb.x + qy * gb.y + qz * gb.z;

  // Endpoints of the crossing segment in homogeneous form: a point (alpha, beta) = numerator /
  // weight. A vertex on the plane is one endpoint (weight 1); an edge whose vertices lie
  // strictly on opposite sides crosses the plane at (d_j (alpha_i, beta_i) - d_i (alpha_j,
  // beta_j)) / (d_j - d_i), computed from the canonical vertex order only, so that every
  // triangle holding the edge gets the same bits. With no vertex on the plane (the common case)
  // one vertex lies alone on its side and the two edges at it cross; otherwise at most two
  // vertices lie on the plane (the coplanar case has returned) and there are at most two
  // endpoints.
  const double a[3] = {alpha[0], alpha[1], alpha[2]};
  const double b[3] = {beta[0], beta[1], beta[2]};
  auto crossing = [&](int i, int j, D2& numerator, double& weight) {
    numerator = d[j] * D2{a[i], b[i]} - d[i] * D2{a[j], b[j]};
    weight = d[j] - d[i];
  };
  D2 numerator[2];
  double weight[2];
  if (d[0] != 0 && d[1] != 0 && d[2] != 0) {
    // The lone vertex's two edges, each as (canonical-less vertex, other).
    static constexpr int kEdgesAt[3][2][2] = {{{0, 1}, {0, 2}}, {{0, 1}, {1, 2}}, {{0, 2}, {1, 2}}};
    const bool n0 = d[0] < 0, n1 = d[1] < 0, n2 = d[2] < 0;
    const int lone = n1 == n2 ? 0 : (n0 == n2 ? 1 : 2);
    for (int e = 0; e < 2; ++e)
      crossing(kEdgesAt[lone][e][0], kEdgesAt[lone][e][1], numerator[e], weight[e]);
  } else {
    int end_count = 0;
    for (int k = 0; k < 3; ++k) {
      if (d[k] != 0) continue;
      numerator[end_count] = D2{a[k], b[k]};
      weight[end_count++] = 1;
    }
    static constexpr int kEdges[3][2] = {{0, 1}, {0, 2}, {1, 2}};  // first vertex canonical-less
    for (const auto& edge : kEdges) {
      const int i = edge[0], j = edge[1];
      if (!((d[i] < 0 && d[j] > 0) || (d[i] > 0 && d[j] < 0))) continue;
      if (end_count == 2) break;  // unreachable for finite input; guards the arrays
      crossing(i, j, numerator[end_count], weight[end_count]);
      ++end_count;
    }
    // A single touching vertex occludes a set of measure zero.
    if (end_count < 2) return std::nullopt;
  }

  // Depth s = alpha + beta of each endpoint, and its projection from x onto the segment's
  // line, t = beta / s: the weights cancel in t, so the two divisions run side by side.
  const D2 depth_numerator = {numerator[0][0] + numerator[0][1], numerator[1][0] + numerator[1][1]};
  const D2 depth = depth_numerator / D2{weight[0], weight[1]};
  D2 t = D2{numerator[0][1], numerator[1][1]} / depth_numerator;

  // Keep the part with depth s in [s_min, s_max]: strictly between x and the segment.
  if (depth[0] <= shadow.s_min && depth[1] <= shadow.s_min) return std::nullopt;
  if (depth[0] >= shadow.s_max && depth[1] >= shadow.s_max) return std::nullopt;
  if (!(std::isfinite(depth[0]) && std::isfinite(depth[1]))) return std::nullopt;
  const bool clip[2] = {depth[0] < shadow.s_min || depth[0] > shadow.s_max,
                        depth[1] < shadow.s_min || depth[1] > shadow.s_max};
  if (clip[0] || clip[1]) {
    // An endpoint beyond s_min or s_max (near x or the light's plane: rare) moves along the
    // crossing segment to that depth (the other endpoint lies on the far side of it, so the
    // denominator is nonzero).
    D2 end[2] = {numerator[0] / weight[0], numerator[1] / weight[1]};
    double end_depth[2] = {depth[0], depth[1]};
    for (int k = 0; k < 2; ++k) {
      if (!clip[k]) continue;
      const double bound = end_depth[k] < shadow.s_min ? shadow.s_min : shadow.s_max;
      const int other = 1 - k;
      const double f = (bound - end_depth[k]) / (end_depth[other] - end_depth[k]);
      end[k] += f * (end[other] - end[k]);
      end_depth[k] = end[k][0] + end[k][1];
      if (!(end_depth[k] > 0)) return std::nullopt;  // rounding guard
      t[k] = end[k][1] / end_depth[k];
    }
  } else if (!(depth[0] > 0 && depth[1] > 0)) {
    return std::nullopt;  // rounding guard
  }

  // The projection is monotone along a segment with s > 0, so the cut is the range of the two.
  const double lo = std::max(std::min(t[0], t[1]), 0.0);
  const double hi = std::min(std::max(t[0], t[1]), 1.0);
  if (!(lo < hi)) return std::nullopt;
  return Interval{lo, hi};
}

}  // namespace penumbra
