#include "core/math/ltc_distribution.h"

#include <cmath>

#include "core/math/polygon_limits.h"
#include "core/math/projected_solid_angle.h"

namespace penumbra {

Vec3 operator*(const Matrix3& a, const Vec3& v) {
  return {a(0, 0) * v.x + a(0, 1) * v.y + a(0, 2) * v.z,
          a(1, 0) * v.x + a(1, 1) * v.y + a(1, 2) * v.z,
          a(2, 0) * v.x + a(2, 1) * v.y + a(2, 2) * v.z};
}

Matrix3 operator*(const Matrix3& a, const Matrix3& b) {
  Matrix3 product;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      product(i, j) = a(i, 0) * b(0, j) + a(i, 1) * b(1, j) + a(i, 2) * b(2, j);
  return product;
}

double determinant(const Matrix3& a) {
  return a(0, 0) * difference_of_products(a(1, 1), a(2, 2), a(1, 2), a(2, 1)) -
         a(0, 1) * difference_of_products(a(1, 0), a(2, 2), a(1, 2), a(2, 0)) +
         a(0, 2) * difference_of_products(a(1, 0), a(2, 1), a(1, 1), a(2, 0));
}

Matrix3 inverse(const Matrix3& a) {
  double det = determinant(a);
  if (!(std::abs(det) > 0) || !std::isfinite(det)) return Matrix3{};
  Matrix3 adjugate;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      // Cofactor of a(j, i): rows and columns other than j and i, in cyclic order.
      int r0 = (j + 1) % 3, r1 = (j + 2) % 3, c0 = (i + 1) % 3, c1 = (i + 2) % 3;
      adjugate(i, j) = difference_of_products(a(r0, c0), a(r1, c1), a(r0, c1), a(r1, c0));
    }
  for (double& entry : adjugate.m) entry /= det;
  return adjugate;
}

LinearlyTransformedCosine::LinearlyTransformedCosine(const Matrix3& m) {
  double det = determinant(m);
  if (!(det > 0) || !std::isfinite(det)) return;  // keep the identity
  m_ = m;
  inverse_ = inverse(m);
  inverse_determinant_ = 1.0 / det;
}

double LinearlyTransformedCosine::density(const Vec3& w) const {
  Vec3 w_cosine = inverse_ * w;
  double length_sq = length_squared(w_cosine);
  if (!(length_sq > 0) || !(w_cosine.z > 0)) return 0;
  // The input's length cancels: scale to |w| = 1 first.
  double w_length_sq = length_squared(w);
  double length_cosine = std::sqrt(length_sq / w_length_sq);
  double cos_theta = w_cosine.z / std::sqrt(length_sq);
  double value =
      kInvPi * cos_theta * inverse_determinant_ / (length_cosine * length_cosine * length_cosine);
  return std::isfinite(value) ? value : 0.0;
}

Vec3 LinearlyTransformedCosine::from_cosine_space(const Vec3& w_cosine) const {
  Vec3 w = m_ * w_cosine;
  double w_length = length(w);
  if (!(w_length > 0) || !std::isfinite(w_length)) return {0, 0, 1};
  return w / w_length;
}

Vec3 LinearlyTransformedCosine::sample(const Vec2& u) const {
  // Cosine-weighted direction (polar map of the disk, lifted), then M.
  double r = std::sqrt(std::clamp(u.x, 0.0, 1.0));
  double phi = 2.0 * kPi * u.y;
  Vec3 w_cosine{r * std::cos(phi), r * std::sin(phi), safe_sqrt(1.0 - u.x)};
  return from_cosine_space(w_cosine);
}

double LinearlyTransformedCosine::polygon_integral(std::span<const Vec3> vertices_local) const {
  if (vertices_local.size() < 3 || vertices_local.size() > size_t(kMaxPolygonVertices)) return 0;
  std::array<Vec3, kMaxPolygonVertices> transformed;
  for (size_t i = 0; i < vertices_local.size(); ++i) transformed[i] = inverse_ * vertices_local[i];
  double integral = projected_solid_angle({transformed.data(), vertices_local.size()}) * kInvPi;
  return std::isfinite(integral) ? integral : 0.0;
}

}  // namespace penumbra
