#pragma once
// 4x4 affine/projective transforms in double precision, with pbrt-v3's conventions: column
// vectors (p' = M p), statements compose on the right (CTM = CTM * T), points take the
// translation, vectors do not, normals transform by the inverse transpose.

#include <array>
#include <cmath>
#include <optional>

#include "core/math/vec.h"

namespace penumbra {

struct Mat4 {
  std::array<std::array<double, 4>, 4> m{};  // m[row][column]

  static Mat4 identity() {
    Mat4 t;
    for (int i = 0; i < 4; ++i) t.m[i][i] = 1;
    return t;
  }
  static Mat4 translate(const Vec3& d) {
    Mat4 t = identity();
    t.m[0][3] = d.x;
    t.m[1][3] = d.y;
    t.m[2][3] = d.z;
    return t;
  }
  static Mat4 scale(const Vec3& s) {
    Mat4 t = identity();
    t.m[0][0] = s.x;
    t.m[1][1] = s.y;
    t.m[2][2] = s.z;
    return t;
  }
  // Rotation by `degrees` about `axis` (normalized here), right-handed as pbrt-v3's Rotate.
  static Mat4 rotate(double degrees, const Vec3& axis) {
    Vec3 a = normalize(axis);
    double theta = degrees * kPi / 180.0;
    double s = std::sin(theta), c = std::cos(theta);
    Mat4 t = identity();
    t.m[0][0] = a.x * a.x + (1 - a.x * a.x) * c;
    t.m[0][1] = a.x * a.y * (1 - c) - a.z * s;
    t.m[0][2] = a.x * a.z * (1 - c) + a.y * s;
    t.m[1][0] = a.x * a.y * (1 - c) + a.z * s;
    t.m[1][1] = a.y * a.y + (1 - a.y * a.y) * c;
    t.m[1][2] = a.y * a.z * (1 - c) - a.x * s;
    t.m[2][0] = a.x * a.z * (1 - c) - a.y * s;
    t.m[2][1] = a.y * a.z * (1 - c) + a.x * s;
    t.m[2][2] = a.z * a.z + (1 - a.z * a.z) * c;
    return t;
  }

  Mat4 operator*(const Mat4& o) const {
    Mat4 r;
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j)
        r.m[i][j] =
            m[i][0] * o.m[0][j] + m[i][1] * o.m[1][j] + m[i][2] * o.m[2][j] + m[i][3] * o.m[3][j];
    return r;
  }

  Vec3 point(const Vec3& p) const {
    double x = m[0][0] * p.x + m[0][1] * p.y + m[0][2] * p.z + m[0][3];
    double y = m[1][0] * p.x + m[1][1] * p.y + m[1][2] * p.z + m[1][3];
    double z = m[2][0] * p.x + m[2][1] * p.y + m[2][2] * p.z + m[2][3];
    double w = m[3][0] * p.x + m[3][1] * p.y + m[3][2] * p.z + m[3][3];
    return w == 1 ? Vec3(x, y, z) : Vec3(x, y, z) / w;
  }
  Vec3 vector(const Vec3& v) const {
    return {m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z,
            m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
            m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z};
  }
  // A normal under this transform: the inverse transpose of the upper 3x3 (`inverse` is this
  // transform's inverse).
  static Vec3 normal(const Mat4& inverse, const Vec3& n) {
    return {inverse.m[0][0] * n.x + inverse.m[1][0] * n.y + inverse.m[2][0] * n.z,
            inverse.m[0][1] * n.x + inverse.m[1][1] * n.y + inverse.m[2][1] * n.z,
            inverse.m[0][2] * n.x + inverse.m[1][2] * n.y + inverse.m[2][2] * n.z};
  }

  // Determinant of the upper 3x3; negative when the transform swaps handedness.
  double determinant3() const {
    return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
           m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  }
  bool is_affine() const { return m[3][0] == 0 && m[3][1] == 0 && m[3][2] == 0 && m[3][3] == 1; }
  bool is_finite() const {
    for (const auto& row : m)
      for (double x : row)
        if (!std::isfinite(x)) return false;
    return true;
  }
  bool operator==(const Mat4&) const = default;

  // Gauss-Jordan elimination with partial pivoting; empty when singular.
  std::optional<Mat4> inverse() const {
    std::array<std::array<double, 8>, 4> a{};
    for (int i = 0; i < 4; ++i) {
      for (int j = 0; j < 4; ++j) a[i][j] = m[i][j];
      a[i][4 + i] = 1;
    }
    for (int column = 0; column < 4; ++column) {
      int pivot = column;
      for (int row = column + 1; row < 4; ++row)
        if (std::abs(a[row][column]) > std::abs(a[pivot][column])) pivot = row;
      if (!(std::abs(a[pivot][column]) > 0)) return std::nullopt;
      std::swap(a[pivot], a[column]);
      double scale = a[column][column];
      if (scale != 1)
        for (double& x : a[column]) x /= scale;
      for (int row = 0; row < 4; ++row) {
        if (row == column || a[row][column] == 0) continue;
        double factor = a[row][column];
        for (int j = 0; j < 8; ++j) a[row][j] -= factor * a[column][j];
      }
    }
    Mat4 r;
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) r.m[i][j] = a[i][4 + j];
    if (!r.is_finite()) return std::nullopt;
    return r;
  }
};

}  // namespace penumbra
