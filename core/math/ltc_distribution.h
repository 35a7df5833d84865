#pragma once
// Linearly transformed cosines (Heitz, Dupuy, Hill & Neubelt 2016; Peters 2021, Sec. 4.1).
//
// A 3x3 matrix M with det M > 0 turns the clamped cosine D_o(w_c) = max(0, w_c.z) / pi into the
// distribution of directions w = M w_c / |M w_c|, whose density per unit solid angle is
//   p_M(w) = D_o(M^-1 w / |M^-1 w|) |det M^-1| / |M^-1 w|^3            (Peters, Sec. 4.1).
// Its integral over a polygon P is the clamped-cosine integral over M^-1 P (Peters Eq. 10), i.e.
// the projected solid angle of the transformed polygon (clipped at z = 0) divided by pi.
// The density does not change when M is scaled, so tables may store M up to a factor.
//
// Everything lives in the local shading frame (z = normal). Double precision throughout: the
// transformed polygon of a narrow lobe (alpha ~ 1e-4) has coordinates ~1e4 times the original.

#include <array>
#include <span>

#include "core/math/vec.h"

namespace penumbra {

// A 3x3 matrix, row-major.
struct Matrix3 {
  std::array<double, 9> m{1, 0, 0, 0, 1, 0, 0, 0, 1};
  double operator()(int row, int column) const { return m[3 * row + column]; }
  double& operator()(int row, int column) { return m[3 * row + column]; }
};

Vec3 operator*(const Matrix3& a, const Vec3& v);
Matrix3 operator*(const Matrix3& a, const Matrix3& b);
double determinant(const Matrix3& a);
// The inverse via the adjugate; the identity for a singular matrix (callers check det first).
Matrix3 inverse(const Matrix3& a);

class LinearlyTransformedCosine {
 public:
  // The identity: the clamped cosine itself (a Lambertian lobe).
  LinearlyTransformedCosine() = default;
  // `m` must have a positive determinant (otherwise the identity is used).
  explicit LinearlyTransformedCosine(const Matrix3& m);

  const Matrix3& matrix() const { return m_; }
  const Matrix3& inverse_matrix() const { return inverse_; }

  // Density per unit solid angle at the direction w (any nonzero length).
  double density(const Vec3& w) const;
  // The unit direction M w_c / |M w_c| for a direction w_c of the cosine space.
  Vec3 from_cosine_space(const Vec3& w_cosine) const;
  // M^-1 w, not normalized (what the polygon's vertices are mapped with).
  Vec3 to_cosine_space(const Vec3& w) const { return inverse_ * w; }
  // A direction distributed with density(): a cosine-distributed direction mapped by M.
  Vec3 sample(const Vec2& u) const;
  // Integral of density() over the polygon with the given vertices (relative to the shading
  // point, local frame, convex, either winding): Peters Eq. 10.
  double polygon_integral(std::span<const Vec3> vertices_local) const;

 private:
  Matrix3 m_;
  Matrix3 inverse_;
  double inverse_determinant_ = 1;  // |det M^-1|
};

}  // namespace penumbra
