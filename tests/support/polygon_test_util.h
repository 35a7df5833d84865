#pragma once
// Shared helpers of the polygon tests: random convex polygons, whether a direction meets one, a
// light facing a point, shading points, brute-force quadrature of solid angle and projected
// solid angle, and a chi-square test of a light strategy's samples against its own pdf, binned
// on the light's plane.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <optional>
#include <random>
#include <vector>

#include "core/lights/shading_point.h"
#include "core/math/vec.h"
#include "core/scene/scene.h"

namespace penumbra::polygon_test {

inline double uniform(std::mt19937_64& rng) {
  return std::uniform_real_distribution<double>(0.0, 1.0)(rng);
}

inline Vec3 random_unit_vector(std::mt19937_64& rng) {
  double z = 2.0 * uniform(rng) - 1.0;
  double phi = 2.0 * kPi * uniform(rng);
  double r = std::sqrt(std::max(0.0, 1.0 - z * z));
  return {r * std::cos(phi), r * std::sin(phi), z};
}

// A convex polygon with `n` vertices on an ellipse of semi-axes (radius, radius * aspect) around
// `center` in the plane with unit normal `normal`, counter-clockwise about the normal.
inline std::vector<Vec3> random_convex_polygon(std::mt19937_64& rng, int n, const Vec3& center,
                                               const Vec3& normal, double radius,
                                               double aspect = 1.0) {
  Frame frame = Frame::from_normal(normal);
  std::vector<double> angles(n);
  for (double& a : angles) a = 2.0 * kPi * uniform(rng);
  std::sort(angles.begin(), angles.end());
  std::vector<Vec3> vertices;
  for (double a : angles)
    vertices.push_back(center + frame.s * (radius * std::cos(a)) +
                       frame.t * (radius * aspect * std::sin(a)));
  return vertices;
}

inline Vec3 polygon_normal(const std::vector<Vec3>& v) {
  return normalize(cross(v[1] - v[0], v[2] - v[0]));
}

// Whether `direction` (from the origin) meets the polygon's plane inside the polygon, up to
// `tolerance` times the polygon's longest edge.
inline bool hits_polygon(const std::vector<Vec3>& polygon, const Vec3& direction,
                         double tolerance) {
  Vec3 n = polygon_normal(polygon);
  double t = dot(n, polygon[0]) / dot(n, direction);
  if (!(t > 0)) return false;
  Vec3 p = direction * t;
  double size = 0;
  for (size_t i = 0; i < polygon.size(); ++i)
    size = std::max(size, length(polygon[(i + 1) % polygon.size()] - polygon[i]));
  for (size_t i = 0; i < polygon.size(); ++i) {
    Vec3 e = polygon[(i + 1) % polygon.size()] - polygon[i];
    if (dot(cross(e, p - polygon[i]), n) / length(e) < -tolerance * size) return false;
  }
  return true;
}

inline Light polygon_light(const std::vector<Vec3>& vertices) {
  Light light;
  light.type = LightType::Polygon;
  light.vertices = vertices;
  light.normal = polygon_normal(vertices);
  return light;
}

// A polygon light whose emitting side faces `x` (vertex order reversed if needed).
inline Light light_facing(std::vector<Vec3> vertices, const Vec3& x) {
  if (dot(polygon_normal(vertices), x - vertices[0]) < 0)
    std::reverse(vertices.begin(), vertices.end());
  return polygon_light(vertices);
}

// A shading point with its normal and outgoing direction normalized.
inline ShadingPoint shading_point(const Vec3& position, const Vec3& normal, const Vec3& wo,
                                  const Material* material) {
  ShadingPoint sp;
  sp.position = position;
  sp.normal = normalize(normal);
  sp.wo = normalize(wo);
  sp.material = material;
  return sp;
}

inline Light quad_light(const Vec3& origin, const Vec3& edge1, const Vec3& edge2) {
  Light light;
  light.type = LightType::Quad;
  light.origin = origin;
  light.edge1 = edge1;
  light.edge2 = edge2;
  light.vertices = {origin, origin + edge1, origin + edge1 + edge2, origin + edge2};
  light.normal = normalize(cross(edge1, edge2));
  light.area = length(cross(edge1, edge2));
  return light;
}

// Integral of f over the polygon (fan triangles, each cut into k^2 sub-triangles, centroid rule).
inline double integrate_over_polygon(const std::vector<Vec3>& v,
                                     const std::function<double(const Vec3&)>& f, int k) {
  double total = 0;
  for (size_t i = 1; i + 1 < v.size(); ++i) {
    Vec3 a = v[0], e1 = (v[i] - v[0]) / k, e2 = (v[i + 1] - v[0]) / k;
    double sub_area = 0.5 * length(cross(e1, e2));
    for (int p = 0; p < k; ++p)
      for (int q = 0; p + q < k; ++q) {
        Vec3 base = a + e1 * p + e2 * q;
        total += f(base + (e1 + e2) / 3.0) * sub_area;  // upright sub-triangle
        if (p + q + 1 < k) total += f(base + (e1 + e2) * (2.0 / 3.0)) * sub_area;  // inverted
      }
  }
  return total;
}

// Solid angle and projected solid angle (about normal) seen from x, by quadrature.
inline double brute_force_solid_angle(const std::vector<Vec3>& v, const Vec3& x, int k = 400) {
  Vec3 n = polygon_normal(v);
  return integrate_over_polygon(
      v,
      [&](const Vec3& p) {
        Vec3 d = p - x;
        double r2 = length_squared(d);
        return std::abs(dot(n, d)) / (r2 * std::sqrt(r2));
      },
      k);
}
inline double brute_force_projected_solid_angle(const std::vector<Vec3>& v, const Vec3& x,
                                                const Vec3& normal, int k = 400) {
  Vec3 n = polygon_normal(v);
  return integrate_over_polygon(
      v,
      [&](const Vec3& p) {
        Vec3 d = p - x;
        double r2 = length_squared(d);
        return std::max(0.0, dot(normal, d)) * std::abs(dot(n, d)) / (r2 * r2);
      },
      k);
}

// Chi-square critical value for `dof` degrees of freedom at the upper tail probability whose
// standard normal quantile is z (Wilson-Hilferty); z = 3.719 is p = 1e-4.
inline double chi_square_critical(int dof, double z = 3.719) {
  double a = 2.0 / (9.0 * dof);
  double b = 1.0 - a + z * std::sqrt(a);
  return dof * b * b * b;
}

struct ChiSquareResult {
  double statistic = 0;
  int dof = 0;
  double critical = 0;
  int missing = 0;  // samples that came back empty
};

// Draws `count` samples with `sample` (returning a point on the light or nothing), bins them on
// a grid x grid raster over the polygon's bounding box in its plane, and compares with the
// probabilities that `pdf_area` integrates to in each bin (sub x sub midpoints per bin, only
// points inside the polygon). Bins expected below 5 are pooled.
inline ChiSquareResult chi_square_on_light(
    const std::vector<Vec3>& polygon, const std::function<std::optional<Vec3>(const Vec2&)>& sample,
    const std::function<double(const Vec3&)>& pdf_area, int count, int grid, uint64_t seed,
    int sub = 12) {
  Vec3 n = polygon_normal(polygon);
  Frame frame = Frame::from_normal(n);
  double min_a = 1e300, max_a = -1e300, min_b = 1e300, max_b = -1e300;
  for (const Vec3& v : polygon) {
    double a = dot(v - polygon[0], frame.s), b = dot(v - polygon[0], frame.t);
    min_a = std::min(min_a, a), max_a = std::max(max_a, a);
    min_b = std::min(min_b, b), max_b = std::max(max_b, b);
  }
  double da = (max_a - min_a) / grid, db = (max_b - min_b) / grid;
  auto inside = [&](const Vec3& p) {
    for (size_t i = 0; i < polygon.size(); ++i) {
      Vec3 e = polygon[(i + 1) % polygon.size()] - polygon[i];
      if (dot(cross(e, p - polygon[i]), n) < 0) return false;
    }
    return true;
  };
  std::vector<double> expected(grid * grid, 0.0), observed(grid * grid, 0.0);
  for (int i = 0; i < grid; ++i)
    for (int j = 0; j < grid; ++j) {
      double sum = 0;
      for (int p = 0; p < sub; ++p)
        for (int q = 0; q < sub; ++q) {
          double a = min_a + (i + (p + 0.5) / sub) * da, b = min_b + (j + (q + 0.5) / sub) * db;
          Vec3 point = polygon[0] + frame.s * a + frame.t * b;
          if (inside(point)) sum += pdf_area(point);
        }
      expected[i * grid + j] = sum * da * db / (sub * sub) * count;
    }
  std::mt19937_64 rng(seed);
  ChiSquareResult result;
  for (int k = 0; k < count; ++k) {
    std::optional<Vec3> p = sample({uniform(rng), uniform(rng)});
    if (!p) {
      ++result.missing;
      continue;
    }
    double a = dot(*p - polygon[0], frame.s), b = dot(*p - polygon[0], frame.t);
    int i = std::clamp(int((a - min_a) / da), 0, grid - 1);
    int j = std::clamp(int((b - min_b) / db), 0, grid - 1);
    observed[i * grid + j] += 1;
  }
  double pooled_expected = 0, pooled_observed = 0;
  int bins = 0;
  for (int i = 0; i < grid * grid; ++i) {
    if (expected[i] < 5) {
      pooled_expected += expected[i];
      pooled_observed += observed[i];
      continue;
    }
    double d = observed[i] - expected[i];
    result.statistic += d * d / expected[i];
    ++bins;
  }
  if (pooled_expected >= 5) {
    double d = pooled_observed - pooled_expected;
    result.statistic += d * d / pooled_expected;
    ++bins;
  } else {
    // Too few expected samples for the statistic (bins at the polygon's corners, whose
    // midpoints may all miss it): only a gross excess fails.
    result.statistic += pooled_observed > 2 * pooled_expected + 20 ? 1e9 : 0.0;
  }
  result.dof = bins - 1;
  result.critical = chi_square_critical(result.dof);
  return result;
}

}  // namespace penumbra::polygon_test
