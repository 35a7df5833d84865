#pragma once
// Arithmetic on Vec2 (core/math/vec.h gives it none): the plane of a local frame's x and y, where
// Peters' projected solid angle sampler works on the projections of directions to the unit disk.

#include <cmath>

#include "core/math/vec.h"

namespace penumbra {

inline Vec2 xy(const Vec3& v) {
  return {v.x, v.y};
}
inline Vec2 add2(const Vec2& a, const Vec2& b) {
  return {a.x + b.x, a.y + b.y};
}
inline Vec2 sub2(const Vec2& a, const Vec2& b) {
  return {a.x - b.x, a.y - b.y};
}
inline Vec2 scale2(const Vec2& a, double s) {
  return {a.x * s, a.y * s};
}
inline double dot2(const Vec2& a, const Vec2& b) {
  return a.x * b.x + a.y * b.y;
}
// z of the 3D cross product, with Kahan's algorithm so that its sign is right (Sec. 3.7).
inline double cross2(const Vec2& a, const Vec2& b) {
  return difference_of_products(a.x, b.y, a.y, b.x);
}
// Peters' R: rotation by 90 degrees counter-clockwise.
inline Vec2 rotate90(const Vec2& a) {
  return {-a.y, a.x};
}
// Plain cross product, where a rounding error in the last bits cannot matter (the safeguard's
// bracket test, the initialization's quad areas).
inline double cross2_plain(const Vec2& a, const Vec2& b) {
  return a.x * b.y - a.y * b.x;
}
inline Vec2 normalize2(const Vec2& a) {
  double l = std::sqrt(dot2(a, a));
  return l > 0 ? scale2(a, 1.0 / l) : a;
}

}  // namespace penumbra
