#pragma once
// Arvo's solid angle sampling of a spherical triangle (Arvo 1995, "Stratified Sampling of
// Spherical Triangles", Sec. 3), in its original trigonometric form, for a convex polygon's
// triangle fan: the named variant `sa-arvo` that polygon_bench compares with Peters' form
// (core/math/solid_angle_polygon.h, which is `sa`). Both implement the same map from [0,1)^2
// to directions (Peters 2021 Sec. 5: the subtriangle (A, B, C') of area u.x * Omega, then the
// arc B -> C' uniform in 1 - cos); Arvo's computes the three interior angles (three acos and
// six cross products) and the area as alpha + beta + gamma - pi, which cancels for small
// triangles (a 1 cm light at 40 m: 6e-8 sr from angles summing to ~pi; measured relative errors
// 1.3e-8 there and 7.9e-7 for 1 mm, against ~1e-12 for Peters' form).
// Kept for the comparison only: not used by the estimator.

#include <array>
#include <optional>
#include <span>

#include "core/math/polygon_limits.h"
#include "core/math/vec.h"

namespace penumbra {

// One spherical triangle prepared for Arvo's algorithm.
struct ArvoSphericalTriangle {
  Vec3 a, b, c;      // unit vertices A, B, C
  Vec3 c_perp_a;     // unit direction of C - (C.A) A (the arc A -> C leaves A along it)
  double alpha = 0;  // interior angle at A
  double cos_alpha = 1;
  double sin_alpha = 0;
  double cos_side_c = 1;  // cos of the side c opposite C: A.B
  double area = 0;        // alpha + beta + gamma - pi (Girard)
};

// Prepares the triangle spanned by the (not necessarily normalized) directions p0, p1, p2.
ArvoSphericalTriangle prepare_arvo_triangle(const Vec3& p0, const Vec3& p1, const Vec3& p2);

// Arvo 1995, Fig. 2: u.x picks the subtriangle area, u.y the point on the arc B -> C'.
Vec3 sample_arvo_triangle(const ArvoSphericalTriangle& triangle, const Vec2& u);

// A convex polygon's triangle fan around vertex 0, each triangle sampled by Arvo's algorithm;
// interface as SolidAnglePolygonSampler.
class ArvoPolygonSampler {
 public:
  explicit ArvoPolygonSampler(std::span<const Vec3> vertices);

  double solid_angle() const { return solid_angle_; }
  double pdf() const { return solid_angle_ > 0 ? 1.0 / solid_angle_ : 0.0; }
  std::optional<Vec3> sample(const Vec2& u) const;

 private:
  int triangle_count_ = 0;
  std::array<ArvoSphericalTriangle, kMaxPolygonVertices - 2> triangles_{};
  double solid_angle_ = 0;
};

}  // namespace penumbra
