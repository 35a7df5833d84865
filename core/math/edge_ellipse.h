#pragma once
// The ellipses of Peters' projected solid angle sampling (Peters 2021, Sec. 3, in homogeneous
// form): the projection to the xy-plane (the unit disk) of the great circle through a polygon
// edge, stored by the circle's unit normal (m, c) = (n_xy, n_z) / |n|; the ellipse is
// q^T C q = c^2 with C = c^2 I + m m^T (Peters' C_j times c^2), so a great circle through the
// zenith (c = 0) needs no special case. core/math/projected_solid_angle.h samples with them;
// core/math/README.md says where this differs from the paper.

#include <array>

#include "core/math/plane_vectors.h"
#include "core/math/vec.h"

namespace penumbra {

// The projection to the xy-plane of the great circle with unit normal (m.x, m.y, c).
struct EdgeEllipse {
  double c = 0;  // z of the unit normal; 0: the great circle passes through the zenith
  Vec2 m;        // xy of the unit normal
};

// The great circle through the directions a and b (not necessarily normalized).
EdgeEllipse edge_ellipse(const Vec3& a, const Vec3& b);

// Signed area of the part of the ellipse's interior in the sector running counter-clockwise
// from direction s0 to direction w (at most 180 degrees): Peters Eq. 1 in homogeneous form,
//   (|c| / 2) atan2(|c| cross(s0, w), s0^T C w).
double ellipse_sector_area(const EdgeEllipse& ellipse, const Vec2& s0, const Vec2& w);

// Squared radius at which the ray through direction w meets the ellipse, and 1 minus it (formed
// without cancellation near the horizon).
double ellipse_radius_squared(const EdgeEllipse& ellipse, const Vec2& w);
double ellipse_one_minus_radius_squared(const EdgeEllipse& ellipse, const Vec2& w);

// The root of the homogeneous quadratic w^T T w = 0 that Peters' Eq. 6 selects (Blinn's stable
// formula specialized to one root; Peters Supplement A.3). T is row-major {xx, xy, yx, yy}.
// The sampler itself solves the same quadratics in step form (see README.md: Eq. 6 picks its
// root by a sign that is rounding noise where the two roots nearly coincide).
Vec2 solve_homogeneous_quadratic(const std::array<double, 4>& t);

// C w with C = c^2 I + m m^T.
inline Vec2 apply_ellipse(const EdgeEllipse& e, const Vec2& w) {
  double mw = dot2(e.m, w);
  return {e.c * e.c * w.x + e.m.x * mw, e.c * e.c * w.y + e.m.y * mw};
}
// a^T C b.
inline double ellipse_form(const EdgeEllipse& e, const Vec2& a, const Vec2& b) {
  return e.c * e.c * dot2(a, b) + dot2(e.m, a) * dot2(e.m, b);
}

// ellipse_radius_squared and ellipse_one_minus_radius_squared with one division.
inline void radius_squared_and_complement(const EdgeEllipse& e, const Vec2& w, double* r2,
                                          double* one_minus_r2) {
  double cw = e.c * e.c * dot2(w, w);
  double mw = dot2(e.m, w);
  double denominator = cw + mw * mw;
  if (!(denominator > 0)) {
    *r2 = 0.0;
    *one_minus_r2 = 1.0;
    return;
  }
  double inverse = 1.0 / denominator;
  *r2 = std::min(1.0, cw * inverse);
  *one_minus_r2 = std::min(1.0, mw * mw * inverse);
}

}  // namespace penumbra
