#pragma once
// Spherical rectangles: Ureña, Fajardo & King 2013, "An area-preserving parametrization for
// spherical rectangles" (EGSR 2013), as reusable free-standing math.
//
// A rectangle (corner, edge ex, edge ey, ex perpendicular to ey) seen from a point o is expressed
// in the local frame of the paper: x along ex, y along ey, z perpendicular and pointing away from
// the rectangle so that the rectangle lies at height z0 < 0. Its corners are (x0|x1, y0|y1, z0).
// The parametrization (u, v) -> point is uniform in solid angle:
//   1. u picks the line x = xu (a line of the rectangle running along ey) so that the solid angle
//      of the sub-rectangle [x0, xu] x [y0, y1] is u * S (the paper's Sec. 4.2, with
//      au = u S + k and the closed form for cos(gamma_u)). cos(au) and sin(au) come from the
//      angle-addition formulas with (cos k, sin k) kept instead of k: no atan2 for k, and u S
//      keeps its relative precision for tiny rectangles instead of being added to k ~ pi.
//   2. v is mapped to h in [h0, h1], h = y / sqrt(d^2 + y^2) with d = sqrt(xu^2 + z0^2) (the
//      projection of the arc's endpoints onto the y axis), and h back to y (Sec. 4.3).
//
// Line sampling (Salesin & Jarosz 2019 Eq. 16-19) uses the two halves separately: `line_x(u)`
// chooses the line, `h_bounds(xu)` gives [h0, h1] of the whole line, `h_of_y` maps the ends of
// each visible y-interval on the line to h, and `y_of_h` maps the h drawn uniformly in the union
// of visible h-intervals back to the line; `point_at(xu, y)` is the point on the rectangle.
// For lines along ex instead of ey, prepare with the edges swapped.
//
// Precision: double. The solid angle is computed with van Oosterom & Strackee's formula on two
// triangles using exact triple products (|det| = |ex| |ey| |z0|), accurate for a 1 cm rectangle
// at 40 m (S ~ 6e-8 sr); the paper's angle sum g0+g1+g2+g3-2pi loses about 1e-8 relative there.
// The interior angles use atan2 forms of the paper's acos(-n_i . n_j), which are closed forms in
// the local coordinates (no normalized plane normals, no acos near +-1).

#include <optional>

#include "core/math/vec.h"

namespace penumbra {

struct SphericalRectangle {
  Vec3 origin;                  // the point o the rectangle is seen from
  Vec3 corner;                  // the corner at local (x0, y0)
  Vec3 x_axis, y_axis, z_axis;  // unit; x along ex, y along ey, z such that z0 < 0
  double x0 = 0, x1 = 0, y0 = 0, y1 = 0, z0 = 0;
  double b0 = 0, b1 = 0;        // n0.z and n2.z of the paper
  double cos_k = 1, sin_k = 0;  // k = 2 pi - g2 - g3
  double solid_angle = 0;
  double z0_squared_over_n0_squared = 0;  // 1 - b0^2, computed without cancellation

  // Prepares the rectangle corner + [0,1] ex + [0,1] ey seen from `o`. Empty when o lies in the
  // rectangle's plane or the rectangle is degenerate (zero solid angle).
  static std::optional<SphericalRectangle> prepare(const Vec3& o, const Vec3& corner,
                                                   const Vec3& ex, const Vec3& ey) {
    SphericalRectangle r;
    double ex_length = length(ex), ey_length = length(ey);
    if (!(ex_length > 0) || !(ey_length > 0)) return std::nullopt;
    r.origin = o;
    r.corner = corner;
    r.x_axis = ex / ex_length;
    r.y_axis = ey / ey_length;
    r.z_axis = normalize(cross(r.x_axis, r.y_axis));
    Vec3 d = corner - o;
    r.z0 = dot(d, r.z_axis);
    if (r.z0 > 0) {
      r.z_axis = -r.z_axis;
      r.z0 = -r.z0;
    }
    if (!(r.z0 < 0)) return std::nullopt;  // o in the rectangle's plane
    r.x0 = dot(d, r.x_axis);
    r.y0 = dot(d, r.y_axis);
    r.x1 = r.x0 + ex_length;
    r.y1 = r.y0 + ey_length;
    // Interior angles (the paper's g_i = acos(-n_i . n_{i+1}), n_i the normals of the planes
    // through o and the edges), written with atan2 in local coordinates.
    double abs_z0 = -r.z0;
    double z0_sq = r.z0 * r.z0;
    auto corner_length = [&](double x, double y) { return std::sqrt(x * x + y * y + z0_sq); };
    // (g0 and g1 enter only through S = g0 + g1 - k, computed more accurately below.)
    // k = 2 pi - (g2 + g3): cos and sin of g2 + g3 from the product of the complex numbers
    // whose arguments are g2 and g3.
    double re2 = r.x0 * r.y1, im2 = abs_z0 * corner_length(r.x0, r.y1);
    double re3 = -r.x0 * r.y0, im3 = abs_z0 * corner_length(r.x0, r.y0);
    double re = difference_of_products(re2, re3, im2, im3), im = re2 * im3 + im2 * re3;
    double modulus = std::sqrt(re * re + im * im);
    if (!(modulus > 0)) return std::nullopt;
    r.cos_k = re / modulus;
    r.sin_k = -im / modulus;
    double n0_length_sq = z0_sq + r.y0 * r.y0;
    double n2_length_sq = z0_sq + r.y1 * r.y1;
    r.b0 = -r.y0 / std::sqrt(n0_length_sq);
    r.b1 = r.y1 / std::sqrt(n2_length_sq);
    r.z0_squared_over_n0_squared = z0_sq / n0_length_sq;
    r.solid_angle = r.solid_angle_up_to(r.x1);
    if (!(r.solid_angle > 0) || !std::isfinite(r.solid_angle)) return std::nullopt;
    return r;
  }

  // Solid angle of the sub-rectangle [x0, x] x [y0, y1] (van Oosterom & Strackee on the two
  // triangles (v00, v10, v11) and (v00, v11, v01); both triple products equal
  // (x - x0) (y1 - y0) |z0| exactly).
  double solid_angle_up_to(double x) const {
    double width = x - x0;
    if (!(width > 0)) return 0;
    Vec3 v00{x0, y0, z0}, v10{x, y0, z0}, v11{x, y1, z0}, v01{x0, y1, z0};
    double l00 = length(v00), l10 = length(v10), l11 = length(v11), l01 = length(v01);
    double triple = width * (y1 - y0) * (-z0);
    double denominator_a =
        l00 * l10 * l11 + dot(v00, v10) * l11 + dot(v00, v11) * l10 + dot(v10, v11) * l00;
    double denominator_b =
        l00 * l11 * l01 + dot(v00, v11) * l01 + dot(v00, v01) * l11 + dot(v11, v01) * l00;
    return 2.0 * angle_sum(denominator_a, triple, denominator_b, triple);
  }

  // arg(a) + arg(b) in [0, 2 pi) for complex numbers a = (re_a, im_a), b = (re_b, im_b) with
  // im >= 0 (angles in [0, pi]): the argument of their product, one atan2 instead of two.
  static double angle_sum(double re_a, double im_a, double re_b, double im_b) {
    double re = difference_of_products(re_a, re_b, im_a, im_b);
    double im = re_a * im_b + im_a * re_b;
    double angle = std::atan2(im, re);
    return angle < 0 ? angle + 2.0 * kPi : angle;
  }

  // Step 1: the x of the line chosen by u in [0,1] (Ureña et al. 2013 Sec. 4.2).
  double line_x(double u) const {
    // au = u S + k by angle addition.
    double partial = u * solid_angle;
    double cos_partial = std::cos(partial), sin_partial = std::sin(partial);
    double cos_au = cos_k * cos_partial - sin_k * sin_partial;
    double sin_au = sin_k * cos_partial + cos_k * sin_partial;
    // fu = (cos(au) b0 - b1) / sin(au); cu = sign(fu) / sqrt(fu^2 + b0^2);
    // xu = -cu z0 / sqrt(1 - cu^2) = sign(fu) |z0| / sqrt(fu^2 - (1 - b0^2)).
    if (sin_au == 0) return std::clamp(0.0, x0, x1);  // fu infinite: cu = 0, xu = 0
    double fu = (cos_au * b0 - b1) / sin_au;
    double denominator = fu * fu - z0_squared_over_n0_squared;
    double xu;
    if (!(denominator > 0)) {
      xu = fu > 0 ? x1 : x0;  // |cu| >= 1: the line is at the far edge in fu's direction
    } else {
      xu = std::copysign(-z0 / std::sqrt(denominator), fu);
    }
    if (!std::isfinite(xu)) xu = fu > 0 ? x1 : x0;
    return std::clamp(xu, x0, x1);
  }

  struct HBounds {
    double d = 0;   // distance from o to the line x = xu within the plane y = 0: sqrt(xu^2+z0^2)
    double h0 = 0;  // h of y0
    double h1 = 0;  // h of y1
  };
  // Step 2 set-up: the h-interval of the whole line x = xu.
  HBounds h_bounds(double xu) const {
    HBounds b;
    b.d = std::sqrt(xu * xu + z0 * z0);
    b.h0 = h_of_y(b.d, y0);
    b.h1 = h_of_y(b.d, y1);
    return b;
  }
  // h = y / sqrt(d^2 + y^2), the projection onto the y axis of the unit direction to (xu, y, z0).
  static double h_of_y(double d, double y) { return y / std::sqrt(d * d + y * y); }
  // The inverse of h_of_y, clamped to the rectangle's [y0, y1].
  double y_of_h(double d, double h) const {
    double one_minus_h_sq = (1.0 - h) * (1.0 + h);
    double y = one_minus_h_sq > 0 ? h * d / std::sqrt(one_minus_h_sq) : (h > 0 ? y1 : y0);
    if (!std::isfinite(y)) y = h > 0 ? y1 : y0;
    return std::clamp(y, y0, y1);
  }

  // Local y of the point a fraction t in [0, 1] along the line (from the edge at y0 to y1), the
  // parameter a shadow-triangle query along the line reports its visible intervals in.
  double y_at_fraction(double t) const { return y0 + t * (y1 - y0); }

  // Salesin & Jarosz Eq. 19: the solid-angle density of a point drawn on a line with h uniform
  // in the union of the line's visible h-intervals, `visible_h_length` their total length and
  // `line_h_length` = h1 - h0 of the whole line. Equals 1 / S when the line is fully visible.
  // (Multiply by cos(theta_light) / r^2 for area measure.) 0 for a fully occluded line.
  double line_sample_solid_angle_pdf(double line_h_length, double visible_h_length) const {
    if (!(visible_h_length > 0) || !(line_h_length > 0)) return 0;
    return line_h_length / (solid_angle * visible_h_length);
  }

  // The point of the rectangle at local (x, y), anchored to the corner so that it lies in the
  // rectangle's plane to the precision of the corner.
  Vec3 point_at(double x, double y) const {
    return corner + (std::clamp(x, x0, x1) - x0) * x_axis + (std::clamp(y, y0, y1) - y0) * y_axis;
  }
  // Local (x, y) of a point of the rectangle.
  Vec2 local_xy(const Vec3& point) const {
    Vec3 d = point - origin;
    return {dot(d, x_axis), dot(d, y_axis)};
  }

  // The point for (u, v) in [0,1]^2, uniform in solid angle.
  Vec3 sample(const Vec2& uv) const {
    double xu = line_x(uv.x);
    HBounds b = h_bounds(xu);
    double hv = b.h0 + uv.y * (b.h1 - b.h0);
    return point_at(xu, y_of_h(b.d, hv));
  }

  // The (u, v) that `sample` maps to `point` (a point of the rectangle).
  Vec2 invert(const Vec3& point) const {
    Vec2 xy = local_xy(point);
    double xu = std::clamp(xy.x, x0, x1);
    double u = std::clamp(solid_angle_up_to(xu) / solid_angle, 0.0, 1.0);
    HBounds b = h_bounds(xu);
    double span = b.h1 - b.h0;
    double v = span > 0
                   ? std::clamp((h_of_y(b.d, std::clamp(xy.y, y0, y1)) - b.h0) / span, 0.0, 1.0)
                   : 0.5;
    return {u, v};
  }
};

}  // namespace penumbra
