#pragma once
// Solid angle sampling of a convex polygon (Peters 2021, Sec. 5).
//
// The polygon is split into a triangle fan around vertex 0. Each spherical triangle's solid angle
// comes from van Oosterom & Strackee's formula (Peters Eq. 13); a triangle is chosen in
// proportion to it. Inside the triangle (v0, v1, v2), Peters' subtriangle construction finds the
// vertex v2' on the arc v0 v2 such that (v0, v1, v2') has the wanted solid angle, and the
// direction is drawn on the arc v1 v2' as in Arvo (1995). The map from [0,1)^2 to directions is
// continuous inside each fan triangle and exactly area preserving, so the density is
// 1 / solid_angle() in solid angle measure.
//
// Precision: double throughout. Triple products are formed from edge vectors of the original
// (unnormalized) polygon, so that tiny and distant polygons (1 mm at 40 m, Peters Fig. 7) keep
// their relative accuracy; Peters uses a Householder reflection for the same purpose.

#include <array>
#include <optional>
#include <span>

#include "core/math/polygon_limits.h"
#include "core/math/spherical_triangle.h"  // triangle_solid_angle (van Oosterom & Strackee)
#include "core/math/vec.h"

namespace penumbra {

// Solid angle of a convex planar polygon seen from the origin (sum over its triangle fan).
double polygon_solid_angle(std::span<const Vec3> vertices);

// One spherical triangle prepared for Peters' subtriangle sampling (Sec. 5).
struct PreparedSphericalTriangle {
  Vec3 v0, v1, v2;  // unit directions, ordered so that det(v0, v1, v2) >= 0
  double g0 = 0;    // det(v0, v1, v2)
  double g1 = 0;    // v0.v2 + v1.v2
  double g2 = 0;    // 1 + v0.v1
  double solid_angle = 0;
};

// Prepares the triangle spanned by the (not necessarily normalized) directions p0, p1, p2.
PreparedSphericalTriangle prepare_spherical_triangle(const Vec3& p0, const Vec3& p1,
                                                     const Vec3& p2);

// Maps u in [0,1)^2 to a unit direction in the triangle, uniformly in solid angle: u.x picks the
// subtriangle's solid angle, u.y the point on its arc v1 v2'.
Vec3 sample_spherical_triangle(const PreparedSphericalTriangle& triangle, const Vec2& u);

// A convex polygon prepared once per shading point for solid angle sampling.
class SolidAnglePolygonSampler {
 public:
  // `vertices`: the polygon's vertices relative to the shading point (any orientation, any
  // frame), convex and planar, 3 to kMaxPolygonVertices of them. More vertices, or fewer than
  // three, give an empty sampler (solid_angle() == 0).
  explicit SolidAnglePolygonSampler(std::span<const Vec3> vertices);

  double solid_angle() const { return solid_angle_; }
  // Density in solid angle measure of every direction inside the polygon (0 if it is empty).
  double pdf() const { return solid_angle_ > 0 ? 1.0 / solid_angle_ : 0.0; }
  // A unit direction towards the polygon; empty if the polygon has no solid angle.
  std::optional<Vec3> sample(const Vec2& u) const;

 private:
  int triangle_count_ = 0;
  std::array<PreparedSphericalTriangle, kMaxPolygonVertices - 2> triangles_{};
  double solid_angle_ = 0;
};

}  // namespace penumbra
