#pragma once
// Shared by the tests of materials, lights and strategies: a deterministic random generator,
// lights and materials built in code (derived fields filled here), and Pearson's chi-square test
// of sample counts against expected counts (bins with expected count < 5 are pooled).

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <sstream>
#include <string>
#include <vector>

#include "core/math/vec.h"
#include "core/scene/scene.h"

namespace penumbra::test {

// SplitMix64: fixed seeds, the same numbers on every platform.
class Rng {
 public:
  explicit Rng(uint64_t seed) : state_(seed) {}
  uint64_t next_bits() {
    uint64_t z = (state_ += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  double uniform() { return static_cast<double>(next_bits() >> 11) * 0x1.0p-53; }
  Vec2 uniform2() {
    double a = uniform();
    return {a, uniform()};
  }
  Vec3 unit_vector() {
    double z = 2.0 * uniform() - 1.0, phi = 2.0 * kPi * uniform();
    double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    return {r * std::cos(phi), r * std::sin(phi), z};
  }

 private:
  uint64_t state_;
};

inline Light quad_light(const Vec3& origin, const Vec3& edge1, const Vec3& edge2,
                        const Rgb& radiance = {1, 1, 1}) {
  Light light;
  light.type = LightType::Quad;
  light.radiance = radiance;
  light.origin = origin;
  light.edge1 = edge1;
  light.edge2 = edge2;
  light.vertices = {origin, origin + edge1, origin + edge1 + edge2, origin + edge2};
  Vec3 c = cross(edge1, edge2);
  light.area = length(c);
  light.normal = c / light.area;
  light.centroid = origin + 0.5 * (edge1 + edge2);
  return light;
}

inline Light polygon_light(const std::vector<Vec3>& vertices, const Rgb& radiance = {1, 1, 1}) {
  Light light;
  light.type = LightType::Polygon;
  light.radiance = radiance;
  light.vertices = vertices;
  light.normal = normalize(cross(vertices[1] - vertices[0], vertices[2] - vertices[0]));
  double area = 0;
  Vec3 weighted;
  for (size_t i = 1; i + 1 < vertices.size(); ++i) {
    double a =
        0.5 * dot(cross(vertices[i] - vertices[0], vertices[i + 1] - vertices[0]), light.normal);
    area += a;
    weighted += a * (vertices[0] + vertices[i] + vertices[i + 1]) / 3.0;
  }
  light.area = area;
  light.centroid = weighted / area;
  return light;
}

inline Light disk_light(const Vec3& center, const Vec3& normal, double radius,
                        const Rgb& radiance = {1, 1, 1}) {
  Light light;
  light.type = LightType::Disk;
  light.radiance = radiance;
  light.center = center;
  light.normal = normalize(normal);
  light.radius = radius;
  light.area = kPi * radius * radius;
  light.centroid = center;
  return light;
}

// A polygon light facing down (-y), the vertex order reversed if needed.
inline Light down_polygon(std::vector<Vec3> vertices) {
  Light light = polygon_light(vertices);
  if (light.normal.y > 0) {
    std::reverse(vertices.begin(), vertices.end());
    light = polygon_light(vertices);
  }
  return light;
}

// A regular convex polygon of `count` vertices, counter-clockwise about `normal`.
inline Light regular_polygon_light(const Vec3& center, const Vec3& normal, double radius, int count,
                                   double rotation = 0.3) {
  Frame frame = Frame::from_normal(normalize(normal));
  std::vector<Vec3> vertices;
  for (int i = 0; i < count; ++i) {
    double phi = rotation + 2.0 * kPi * i / count;
    vertices.push_back(center + radius * (std::cos(phi) * frame.s + std::sin(phi) * frame.t));
  }
  Light light = polygon_light(vertices);
  if (dot(light.normal, normal) < 0) {
    std::reverse(vertices.begin(), vertices.end());
    light = polygon_light(vertices);
  }
  return light;
}

inline Material lambert(const Rgb& albedo = {0.8, 0.8, 0.8}) {
  Material m;
  m.name = "lambert";
  m.type = MaterialType::Lambert;
  m.albedo = albedo;
  return m;
}
inline Material phong(const Rgb& kd, const Rgb& ks, double exponent) {
  Material m;
  m.name = "phong";
  m.type = MaterialType::Phong;
  m.kd = kd;
  m.ks = ks;
  m.exponent = exponent;
  return m;
}
inline Material ggx(const Rgb& diffuse, const Rgb& specular, double roughness) {
  Material m;
  m.name = "ggx";
  m.type = MaterialType::Ggx;
  m.diffuse = diffuse;
  m.specular = specular;
  m.roughness = roughness;
  return m;
}

// Upper quantile of the chi-square distribution with `dof` degrees of freedom at significance
// `alpha` (only 1e-3, 1e-4 and 1e-5 are tabulated), by the Wilson-Hilferty approximation
// (accurate to well under 1% of the quantile for dof >= 10).
inline double chi_square_critical(int dof, double alpha) {
  double z = alpha >= 1e-3 ? 3.0902 : (alpha >= 1e-4 ? 3.7190 : 4.2649);
  double k = dof;
  double a = 2.0 / (9.0 * k);
  double c = 1.0 - a + z * std::sqrt(a);
  return k * c * c * c;
}

struct ChiSquareResult {
  double statistic = 0;
  int dof = 0;
  double critical = 0;
  bool passed = false;
  std::string summary() const {
    std::ostringstream out;
    out << "chi2 = " << statistic << " with " << dof << " dof, critical " << critical;
    return out.str();
  }
};

// Pearson's test. Bins with expected < 5 are pooled into one bin (added to the smallest regular
// bin when the pool itself stays below 5).
inline ChiSquareResult chi_square_test(std::span<const double> observed,
                                       std::span<const double> expected, double alpha = 1e-4) {
  std::vector<std::pair<double, double>> bins;  // (expected, observed)
  double pooled_expected = 0, pooled_observed = 0;
  for (size_t i = 0; i < observed.size(); ++i) {
    if (expected[i] < 5) {
      pooled_expected += expected[i];
      pooled_observed += observed[i];
    } else {
      bins.emplace_back(expected[i], observed[i]);
    }
  }
  if (pooled_expected >= 5) {
    bins.emplace_back(pooled_expected, pooled_observed);
  } else if (!bins.empty()) {
    auto smallest = std::min_element(bins.begin(), bins.end());
    smallest->first += pooled_expected;
    smallest->second += pooled_observed;
  }
  ChiSquareResult result;
  for (const auto& [e, o] : bins) result.statistic += (o - e) * (o - e) / e;
  result.dof = static_cast<int>(bins.size()) - 1;
  if (result.dof < 1) return result;
  result.critical = chi_square_critical(result.dof, alpha);
  result.passed = result.statistic <= result.critical;
  return result;
}

inline double relative_difference(double a, double b) {
  double scale = std::max(std::abs(a), std::abs(b));
  return scale > 0 ? std::abs(a - b) / scale : 0.0;
}

}  // namespace penumbra::test
