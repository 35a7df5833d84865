#pragma once
// Small vector types for core math. Double precision throughout core: sampling math of
// spherical polygons and line integrals loses too much in float; Embree rays are float and
// converted at the Embree boundary (core/render/embree_scene.h).

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace penumbra {

struct Vec2 {
  double x = 0, y = 0;
  constexpr Vec2() = default;
  constexpr Vec2(double x_, double y_) : x(x_), y(y_) {}
  constexpr double operator[](int i) const { return i == 0 ? x : y; }
  constexpr double& operator[](int i) { return i == 0 ? x : y; }
};

struct Vec3 {
  double x = 0, y = 0, z = 0;
  constexpr Vec3() = default;
  constexpr Vec3(double x_, double y_, double z_) : x(x_), y(y_), z(z_) {}
  constexpr double operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  constexpr double& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
  constexpr Vec3 operator-() const { return {-x, -y, -z}; }
  constexpr Vec3& operator+=(const Vec3& o) {
    x += o.x;
    y += o.y;
    z += o.z;
    return *this;
  }
  constexpr Vec3& operator-=(const Vec3& o) {
    x -= o.x;
    y -= o.y;
    z -= o.z;
    return *this;
  }
  constexpr Vec3& operator*=(double s) {
    x *= s;
    y *= s;
    z *= s;
    return *this;
  }
  constexpr Vec3& operator/=(double s) {
    x /= s;
    y /= s;
    z /= s;
    return *this;
  }
};

// RGB radiance and reflectance share the vector type; names say which is meant.
using Rgb = Vec3;

constexpr Vec3 operator+(Vec3 a, const Vec3& b) {
  return a += b;
}
constexpr Vec3 operator-(Vec3 a, const Vec3& b) {
  return a -= b;
}
constexpr Vec3 operator*(Vec3 a, double s) {
  return a *= s;
}
constexpr Vec3 operator*(double s, Vec3 a) {
  return a *= s;
}
constexpr Vec3 operator/(Vec3 a, double s) {
  return a /= s;
}
// Component-wise product (RGB times RGB).
constexpr Vec3 operator*(const Vec3& a, const Vec3& b) {
  return {a.x * b.x, a.y * b.y, a.z * b.z};
}
constexpr bool operator==(const Vec3& a, const Vec3& b) {
  return a.x == b.x && a.y == b.y && a.z == b.z;
}

constexpr double dot(const Vec3& a, const Vec3& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
constexpr Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double length_squared(const Vec3& a) {
  return dot(a, a);
}
inline double length(const Vec3& a) {
  return std::sqrt(dot(a, a));
}
inline Vec3 normalize(const Vec3& a) {
  return a / length(a);
}
inline double max_component(const Vec3& a) {
  return std::max(a.x, std::max(a.y, a.z));
}
inline double luminance(const Rgb& c) {
  return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
}
inline bool is_finite(const Vec3& a) {
  return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z);
}
inline bool is_black(const Rgb& c) {
  return c.x == 0 && c.y == 0 && c.z == 0;
}

// Numerics guards, named for what they guard.

// a*b - c*d without catastrophic cancellation (Kahan's algorithm with an FMA).
inline double difference_of_products(double a, double b, double c, double d) {
  double cd = c * d;
  double err = std::fma(-c, d, cd);
  double dop = std::fma(a, b, -cd);
  return dop + err;
}
// Cross product with difference_of_products per component (Peters Sec. 3.7).
inline Vec3 cross_accurate(const Vec3& a, const Vec3& b) {
  return {difference_of_products(a.y, b.z, a.z, b.y), difference_of_products(a.z, b.x, a.x, b.z),
          difference_of_products(a.x, b.y, a.y, b.x)};
}
inline double safe_sqrt(double x) {
  return std::sqrt(std::max(0.0, x));
}
inline double safe_acos(double x) {
  return std::acos(std::clamp(x, -1.0, 1.0));
}
inline double safe_asin(double x) {
  return std::asin(std::clamp(x, -1.0, 1.0));
}

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kInvPi = 0.31830988618379067154;

// Orthonormal basis around a unit normal (Duff et al. 2017, branchless).
struct Frame {
  Vec3 s, t, n;
  static Frame from_normal(const Vec3& n) {
    double sign = std::copysign(1.0, n.z);
    double a = -1.0 / (sign + n.z);
    double b = n.x * n.y * a;
    Frame f;
    f.s = {1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x};
    f.t = {b, sign + n.y * n.y * a, -n.y};
    f.n = n;
    return f;
  }
  Vec3 to_local(const Vec3& v) const { return {dot(v, s), dot(v, t), dot(v, n)}; }
  Vec3 to_world(const Vec3& v) const { return s * v.x + t * v.y + n * v.z; }
};

}  // namespace penumbra
