#pragma once
// The shadow-pyramid query: which occluder triangles can hide part of a polygonal light from a
// shading point x. The pyramid is the convex cone from x through the light polygon, cut at the
// light's plane: an occluder can cut the light only where it crosses the pyramid. The query walks
// the line query's BVH (core/lines/line_query.h: the same nodes and float triangles, so shared
// edges stay shared) and keeps the triangles whose boxes, then whose vertices, are not entirely
// outside one of the pyramid's planes (the side planes through x and each light edge, and the
// light's plane). It is conservative: every triangle that can cut the light is returned, and
// some that cannot (the clipping in core/exact/visible_light.h removes nothing for those).
//
// It is a separate traversal: the line query's own walk is untouched.

#include <cstdint>
#include <span>
#include <vector>

#include "core/lines/line_query.h"
#include "core/math/vec.h"

namespace penumbra {

// A plane n.p <= offset (inside) with n not necessarily unit.
struct HalfSpace {
  Vec3 normal;
  double offset = 0;
  double side(const Vec3& p) const { return dot(normal, p) - offset; }  // <= 0 inside
};

// The pyramid from x through a convex light polygon (either winding): one half-space per edge
// (through x and the edge, the light's centroid inside) and the light plane (x's side inside).
// Empty when x lies in the light's plane or the polygon is degenerate.
std::vector<HalfSpace> shadow_pyramid(const Vec3& x, std::span<const Vec3> light_polygon);

// Indices into query.triangles() of the occluders that may cross the pyramid.
void occluders_in_pyramid(const LineQuery& query, std::span<const HalfSpace> pyramid,
                          std::vector<uint32_t>& out);

}  // namespace penumbra
