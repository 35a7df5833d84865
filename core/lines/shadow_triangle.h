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

#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include "core/lines/intervals.h"
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
  // s_min as a distance: s_min times the distance from x to the segment's line. An occluder
  // whose plane passes this close to x is seen edge-on (the surface x lies on, or coplanar with
  // it) and does not occlude.
  double self_occlusion_distance = 0;
  double self_occlusion_distance_squared = 0;

  // The shadow triangle of x and segment a->b, or empty when it is degenerate (a == b, x on the
  // segment's line or too close to it for the plane to be defined, non-finite input).
  static std::optional<ShadowTriangle> make(const Vec3& x, const Vec3& a, const Vec3& b,
                                            const ShadowTriangleTolerances& tolerances = {});
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
// (36 bytes instead of 72: large scenes are bound by memory traffic), in canonical order.
// Everything computed from them is double precision; the rounding is per vertex, so shared
// vertices stay shared and closed meshes stay closed.
struct OccluderTriangle {
  float v[3][3];

  Vec3 vertex(int k) const { return {v[k][0], v[k][1], v[k][2]}; }
  // Empty for triangles that cannot occlude: non-finite or zero area after rounding.
  static std::optional<OccluderTriangle> make(const Vec3& v0, const Vec3& v1, const Vec3& v2);
};

// The closed interval of t an occluder triangle removes from the segment, or empty when it
// does not cross the shadow triangle strictly between x and the segment.
// - Occluders whose plane passes through x (within ShadowTriangle::self_occlusion_distance)
//   are seen edge-on and do not occlude: the surface x lies on and its coplanar neighbours
//   (rounding would otherwise give them sliver cuts, false visibility boundaries).
// - Coplanar occluders (lying in the shadow plane) do not occlude: such configurations have
//   measure zero, and in a closed mesh their neighbours still cut along the shared edges.
// - Zero-length cuts are reported empty.
std::optional<Interval> occluder_cut(const ShadowTriangle& shadow,
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

}  // namespace penumbra
