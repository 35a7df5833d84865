#include "core/math/edge_ellipse.h"

#include <algorithm>
#include <cmath>

namespace penumbra {

namespace {

// |c| below this is treated as a great circle through the zenith: c^2 would underflow.
constexpr double kZenithCircleC = 1e-140;

}  // namespace

EdgeEllipse edge_ellipse(const Vec3& a, const Vec3& b) {
  Vec3 n = cross_accurate(a, b);
  double l = length(n);
  EdgeEllipse e;
  if (!(l > 0) || !std::isfinite(l)) return e;  // a and b in the same direction: no arc
  e.c = n.z / l;
  e.m = {n.x / l, n.y / l};
  if (std::abs(e.c) < kZenithCircleC) e.c = 0;
  return e;
}

double ellipse_sector_area(const EdgeEllipse& e, const Vec2& s0, const Vec2& w) {
  double abs_c = std::abs(e.c);
  if (abs_c == 0) return 0.0;
  return 0.5 * abs_c * std::atan2(abs_c * cross2(s0, w), ellipse_form(e, s0, w));
}

double ellipse_radius_squared(const EdgeEllipse& e, const Vec2& w) {
  double denominator = ellipse_form(e, w, w);
  return denominator > 0 ? std::min(1.0, e.c * e.c * dot2(w, w) / denominator) : 0.0;
}

double ellipse_one_minus_radius_squared(const EdgeEllipse& e, const Vec2& w) {
  double denominator = ellipse_form(e, w, w);
  double mw = dot2(e.m, w);
  return denominator > 0 ? std::min(1.0, mw * mw / denominator) : 1.0;
}

Vec2 solve_homogeneous_quadratic(const std::array<double, 4>& t) {
  // w^T T w = t_xx w_x^2 + (t_xy + t_yx) w_x w_y + t_yy w_y^2 = 0 (Peters Eq. 6).
  double half_b = 0.5 * (t[1] + t[2]);
  double root = safe_sqrt(difference_of_products(half_b, half_b, t[0], t[3]));
  if (half_b >= 0) return {half_b + root, -t[0]};
  return {t[3], -half_b + root};
}

}  // namespace penumbra
