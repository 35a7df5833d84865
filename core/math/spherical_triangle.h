#pragma once
// The solid angle of a spherical triangle: van Oosterom & Strackee 1983, a single atan2
// (Peters 2021 Eq. 13). Sampling spherical triangles and polygons uniformly in solid angle lives
// in core/math/solid_angle_polygon.h (Peters 2021 Sec. 5, the `sa` of polygons), Arvo's
// original form in core/math/arvo_solid_angle.h (for comparison).
//
// Double precision: a 1 cm light at 40 m subtends 6e-8 sr; the triple product is formed from the
// edge vectors b - a and c - a, which carry the triangle's size without the cancellation that
// det(a, b, c) suffers when a, b, c are nearly parallel: relative error about 1e-12 there.

#include <cmath>

#include "core/math/vec.h"

namespace penumbra {

// Solid angle of the triangle with vertices a, b, c seen from the origin (either orientation;
// a, b, c need not be unit; 0 when a vertex is at the origin):
// tan(omega / 2) = |a.(b x c)| / (|a||b||c| + (a.b)|c| + (a.c)|b| + (b.c)|a|).
inline double triangle_solid_angle(const Vec3& a, const Vec3& b, const Vec3& c) {
  double la = length(a), lb = length(b), lc = length(c);
  if (!(la > 0 && lb > 0 && lc > 0)) return 0.0;
  double triple = dot(a, cross_accurate(b - a, c - a));
  double denominator = la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la;
  double omega = 2.0 * std::atan2(std::abs(triple), denominator);
  return std::isfinite(omega) ? omega : 0.0;
}

}  // namespace penumbra
