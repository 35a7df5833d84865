#pragma once
// The horizon clip of a polygon: the one implementation behind Lambert's formula
// (core/math/lambert_polygon.h), the exact visible light (core/exact) and Peters' projected
// solid angle (core/math/projected_solid_angle.h, in the local frame n = z).

#include <cstddef>
#include <span>

#include "core/math/vec.h"

namespace penumbra {

// Sutherland-Hodgman clip of a polygon (given as vectors relative to x) against the half-space
// dot(n, w) >= 0. Writes at most vertices.size() + 1 vertices to `out`; returns their count.
inline size_t clip_polygon_to_horizon(std::span<const Vec3> relative_vertices, const Vec3& n,
                                      std::span<Vec3> out) {
  size_t count = 0;
  size_t size = relative_vertices.size();
  for (size_t i = 0; i < size; ++i) {
    const Vec3& a = relative_vertices[i];
    const Vec3& b = relative_vertices[(i + 1) % size];
    double height_a = dot(n, a), height_b = dot(n, b);
    if (height_a >= 0) out[count++] = a;
    // The edge crosses the horizon strictly: add the crossing point.
    if ((height_a > 0 && height_b < 0) || (height_a < 0 && height_b > 0)) {
      double t = height_a / (height_a - height_b);
      Vec3 crossing = a + t * (b - a);
      crossing -= dot(n, crossing) * n;  // exactly on the horizon up to rounding
      out[count++] = crossing;
    }
  }
  return count;
}

}  // namespace penumbra
