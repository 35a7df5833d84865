#include "core/math/arvo_solid_angle.h"

#include <algorithm>
#include <cmath>

namespace penumbra {

namespace {

// The interior angle at vertex p of the spherical triangle (p, q, r): the angle between the
// planes of the great circles p q and p r.
double interior_angle(const Vec3& p, const Vec3& q, const Vec3& r) {
  Vec3 n_pq = cross(p, q), n_pr = cross(p, r);
  double l = length(n_pq) * length(n_pr);
  if (!(l > 0)) return 0.0;
  return std::acos(std::clamp(dot(n_pq, n_pr) / l, -1.0, 1.0));
}

Vec3 unit_or_zero(const Vec3& v) {
  double l = length(v);
  return l > 0 ? v / l : Vec3{0, 0, 0};
}

}  // namespace

ArvoSphericalTriangle prepare_arvo_triangle(const Vec3& p0, const Vec3& p1, const Vec3& p2) {
  ArvoSphericalTriangle t;
  double l0 = length(p0), l1 = length(p1), l2 = length(p2);
  if (!(l0 > 0 && l1 > 0 && l2 > 0) || !std::isfinite(l0 * l1 * l2)) return t;
  t.a = p0 / l0;
  t.b = p1 / l1;
  t.c = p2 / l2;
  double alpha = interior_angle(t.a, t.b, t.c);
  double beta = interior_angle(t.b, t.c, t.a);
  double gamma = interior_angle(t.c, t.a, t.b);
  t.alpha = alpha;
  t.cos_alpha = std::cos(alpha);
  t.sin_alpha = std::sin(alpha);
  t.cos_side_c = dot(t.a, t.b);
  t.c_perp_a = unit_or_zero(t.c - dot(t.c, t.a) * t.a);
  // Girard's theorem (Arvo's area).
  t.area = alpha + beta + gamma - kPi;
  if (!std::isfinite(t.area) || t.area < 0 || !(t.sin_alpha > 0)) t.area = 0;
  return t;
}

Vec3 sample_arvo_triangle(const ArvoSphericalTriangle& t, const Vec2& u) {
  // Arvo 1995, Fig. 2, steps 1-8: C' on the arc A -> C bounds the subtriangle of area A_hat.
  double area_hat = u.x * t.area;
  double s = std::sin(area_hat - t.alpha);
  double tc = std::cos(area_hat - t.alpha);
  double uu = tc - t.cos_alpha;
  double v = s + t.sin_alpha * t.cos_side_c;
  double denominator = (v * s + uu * tc) * t.sin_alpha;
  double q = denominator != 0 ? ((v * tc - uu * s) * t.cos_alpha - v) / denominator : 1.0;
  q = std::clamp(q, -1.0, 1.0);
  Vec3 c_prime = q * t.a + safe_sqrt(1.0 - q * q) * t.c_perp_a;
  // Steps 9-11: the point on the arc B -> C' with 1 - cos uniform.
  double z = 1.0 - u.y * (1.0 - dot(c_prime, t.b));
  z = std::clamp(z, -1.0, 1.0);
  Vec3 direction =
      z * t.b + safe_sqrt(1.0 - z * z) * unit_or_zero(c_prime - dot(c_prime, t.b) * t.b);
  return normalize(direction);
}

ArvoPolygonSampler::ArvoPolygonSampler(std::span<const Vec3> vertices) {
  int n = static_cast<int>(vertices.size());
  if (n < 3 || n > kMaxPolygonVertices) return;
  for (int i = 1; i + 1 < n; ++i) {
    ArvoSphericalTriangle t = prepare_arvo_triangle(vertices[0], vertices[i], vertices[i + 1]);
    if (t.area > 0) {
      triangles_[triangle_count_++] = t;
      solid_angle_ += t.area;
    }
  }
  if (!(solid_angle_ > 0) || !std::isfinite(solid_angle_)) {
    solid_angle_ = 0;
    triangle_count_ = 0;
  }
}

std::optional<Vec3> ArvoPolygonSampler::sample(const Vec2& u) const {
  if (triangle_count_ == 0) return std::nullopt;
  double target = u.x * solid_angle_;
  int chosen = triangle_count_ - 1;
  double before = 0;
  for (int i = 0; i < triangle_count_; ++i) {
    if (target < before + triangles_[i].area || i == triangle_count_ - 1) {
      chosen = i;
      break;
    }
    before += triangles_[i].area;
  }
  const ArvoSphericalTriangle& t = triangles_[chosen];
  double local = std::clamp((target - before) / t.area, 0.0, 1.0);
  Vec3 direction = sample_arvo_triangle(t, {local, u.y});
  if (!is_finite(direction)) return std::nullopt;
  return direction;
}

}  // namespace penumbra
