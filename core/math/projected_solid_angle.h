#pragma once
// Projected solid angle sampling of convex polygons (Peters 2021, Sec. 3).
//
// Input: the polygon's vertices relative to the shading point, in its local frame (z = shading
// normal). By the Nusselt analog, sampling the cosine-weighted solid angle of the polygon is
// sampling the area of its projection onto the unit disk (the xy-plane) uniformly. Each edge is
// an arc of a great circle whose projection is an ellipse centred at the origin. Rays from the
// origin through the projected vertices cut the disk into sectors (Sec. 3.1):
//   - central case (the zenith lies in the polygon): each sector holds one ellipse arc, and the
//     area up to a direction inverts in closed form (Sec. 3.2);
//   - decentral case: each sector lies between an inner and an outer ellipse; the direction that
//     reaches a given area is found by Peters' tangent-line iteration (Sec. 3.3), started from the
//     two-quad initialization (Sec. 3.4). Their quadratics are solved in step form with the root
//     chosen by the residual's sign (README.md says why, and what else differs from the paper).
// The radius is then drawn so that the area is uniform, and the point is lifted to the
// hemisphere (Eq. 2). The density is 1 / projected_solid_angle() in projected solid angle
// measure (p(w) = cos(theta) / projected_solid_angle() in solid angle measure).
//
// Representation and precision (Sec. 3.7): everything is double. An edge's great circle is
// stored by its unit normal (m, c) = (n_xy, n_z) / |n| with n = v_j x v_{j+1} formed by Kahan's
// cross product (cross_accurate). The ellipse is q^T C q = c^2 with C = c^2 I + m m^T, i.e.
// Peters' C_j multiplied by c^2. This homogeneous form never divides by c = n_z, so great
// circles through the zenith (c = 0, Peters' Supplement A.2: edges parallel to the normal, as in
// his Fig. 12) need no special formulas: such an ellipse degenerates to a segment and encloses
// no area. Directions in the plane are used without normalization where their length cancels.

#include <array>
#include <optional>
#include <span>

#include "core/math/edge_ellipse.h"
#include "core/math/polygon_limits.h"
#include "core/math/vec.h"

namespace penumbra {

// Closed-form projected solid angle of a convex polygon given relative to the shading point in
// its local frame: the part above the horizon, by Lambert's formula
//   (1/2) sum_j angle(v_j, v_{j+1}) * (n_j . z) / |n_j|,  n_j = v_j x v_{j+1}.
// Independent of the polygon's orientation. 0 for fewer than 3 or more than kMaxPolygonVertices.
double projected_solid_angle(std::span<const Vec3> vertices_local);

// A convex polygon prepared once per shading point for projected solid angle sampling.
class ProjectedSolidAngleSampler {
 public:
  // Peters: two iterations suffice in 80-bit arithmetic (Sec. 3.6); double precision may use a
  // third. At most three here, the third only where the residual after the first was above
  // 1e-6 of the sector: with two, our random configurations keep worst backward errors of a few
  // 1e-6 near the polygon's ends (where the ellipses meet and convergence is slower); with the
  // conditional third, 1.2e-6 at worst on 10^6 configurations and 2.7e-13 at the 99th
  // percentile (projected_solid_angle_test.cpp).
  static constexpr int kDefaultIterations = 3;

  // `vertices_local`: relative to the shading point, in its local frame (z = normal); convex,
  // planar, 3 to kMaxPolygonVertices vertices, either winding. Polygons with nothing above the
  // horizon, or seen edge-on, give an empty sampler (projected_solid_angle() == 0).
  explicit ProjectedSolidAngleSampler(std::span<const Vec3> vertices_local,
                                      int iterations = kDefaultIterations);

  // Area of the projection to the unit disk (sum of the sector areas).
  double projected_solid_angle() const { return total_area_; }
  // Density in projected solid angle measure of every sampled direction.
  double pdf() const { return total_area_ > 0 ? 1.0 / total_area_ : 0.0; }
  // True if the zenith is inside (or on the boundary of) the clipped polygon.
  bool is_central() const { return central_; }
  int sector_count() const { return sector_count_; }

  // Maps u in [0,1)^2 to a unit direction in the local frame with z >= 0: u.x chooses the
  // azimuth (area in sector order), u.y the radius. Continuous in u within each sector.
  std::optional<Vec3> sample(const Vec2& u) const;

  // The inverse of sample: the primary sample that maps to `direction` (any length, z >= 0);
  // empty if it points outside the polygon's projection.
  std::optional<Vec2> invert(const Vec3& direction) const;

  // Peters' backward error (Sec. 3.6) of a direction produced for u: the difference between the
  // area the sample should have reached within its sector and the area it reaches, divided by
  // the sector's area (which perturbation of u.x, in sector units, explains the result).
  double backward_error(const Vec2& u, const Vec3& direction) const;
  // How much cancellation the area of the sector that u.x selects suffers: the outer ellipse's
  // sector area over the sector's area (1 in the central case). Near 1e16 the area, and so the
  // backward error, is rounding noise (slivers of ~1e-17 sr at the horizon or seen edge-on).
  double area_cancellation(double u0) const;

 private:
  struct Sector {
    Vec2 s0, s1;            // boundaries (vertices' xy), counter-clockwise from s0 to s1
    Vec2 s0_unit, s1_unit;  // the same, normalized
    Vec2 half;              // their bisector (Peters Eq. 8)
    EdgeEllipse inner;      // c == 0: no inner ellipse (the origin bounds the sector)
    EdgeEllipse outer;
    double area = 0;   // projected solid angle inside the sector
    double angle = 0;  // single ellipse: its sector angle in the circle it maps to
  };

  // Sector for the area u0 * total, and the area still to cover inside it.
  int select_sector(double u0, double* area_in_sector) const;
  // Area of sector `sector` from its boundary s0 to direction w.
  double area_up_to(const Sector& sector, const Vec2& w) const;
  Vec2 single_ellipse_direction(const Sector& sector, double area) const;
  Vec2 two_ellipse_direction(const Sector& sector, double area) const;
  void add_sector(const Vec2& s0, const Vec2& s1, const EdgeEllipse& inner,
                  const EdgeEllipse& outer);

  std::array<Sector, kMaxClippedPolygonVertices> sectors_{};
  int sector_count_ = 0;
  double total_area_ = 0;
  bool central_ = false;
  int iterations_ = kDefaultIterations;
};

}  // namespace penumbra
