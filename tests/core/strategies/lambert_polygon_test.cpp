// core/math/lambert_polygon.h against brute-force quadrature of the area integral
// F = integral max(0, cos_x) |cos_l| / (pi r^2) dA, including polygons that cross the horizon,
// and the one-sided radiance (0 behind the light).

#include "core/math/lambert_polygon.h"

#include <gtest/gtest.h>

#include <vector>

#include "tests/core/strategies/test_support.h"

namespace penumbra {
namespace {

using test::relative_difference;

// Midpoint rule on the fan triangles, each cut into m^2 congruent sub-triangles.
double brute_force_form_factor(const Vec3& x, const Vec3& n, const std::vector<Vec3>& polygon,
                               int m = 300) {
  Vec3 normal = normalize(cross(polygon[1] - polygon[0], polygon[2] - polygon[0]));
  double total = 0;
  for (size_t k = 1; k + 1 < polygon.size(); ++k) {
    Vec3 a = polygon[0], e1 = (polygon[k] - a) / m, e2 = (polygon[k + 1] - a) / m;
    double sub_area = 0.5 * length(cross(e1, e2));
    auto integrand = [&](const Vec3& p) {
      Vec3 d = p - x;
      double r2 = length_squared(d);
      double cos_x = std::max(0.0, dot(n, d)) / std::sqrt(r2);
      double cos_l = std::abs(dot(normal, d)) / std::sqrt(r2);
      return cos_x * cos_l / (kPi * r2);
    };
    for (int i = 0; i < m; ++i)
      for (int j = 0; i + j < m; ++j) {
        // Upward sub-triangle (i, j), (i+1, j), (i, j+1) and, when it exists, the downward one.
        Vec3 base = a + double(i) * e1 + double(j) * e2;
        total += integrand(base + (e1 + e2) / 3.0) * sub_area;
        if (i + j + 1 < m) total += integrand(base + (2.0 * e1 + 2.0 * e2) / 3.0) * sub_area;
      }
  }
  return total;
}

struct Configuration {
  std::string name;
  Vec3 x, n;
  std::vector<Vec3> polygon;
};

std::vector<Configuration> configurations() {
  std::vector<Vec3> square = {{-0.5, 1, -0.5}, {-0.5, 1, 0.5}, {0.5, 1, 0.5}, {0.5, 1, -0.5}};
  std::vector<Vec3> triangle = {{-0.2, 0.8, 0.1}, {0.6, 1.2, 0.4}, {0.3, 1.0, -0.5}};
  std::vector<Vec3> pentagon;
  for (int i = 0; i < 5; ++i) {
    double phi = 0.4 + 2 * kPi * i / 5;
    pentagon.push_back(Vec3{0.6 * std::cos(phi), 0.5 + 0.3 * std::sin(phi), 0.6 * std::sin(phi)});
  }
  return {
      {"square_overhead", {0, 0, 0}, {0, 1, 0}, square},
      {"square_tilted_receiver", {0.2, 0, 0.1}, normalize(Vec3{0.5, 1, 0.2}), square},
      {"triangle", {0.1, 0, 0}, {0, 1, 0}, triangle},
      {"pentagon", {0, -0.2, 0}, {0, 1, 0}, pentagon},
      // The receiver's horizon cuts through the polygons.
      {"square_crossing_horizon", {0, 0.6, 0}, normalize(Vec3{1, 0.3, 0}), square},
      {"pentagon_crossing_horizon", {0, 0.0, 0}, normalize(Vec3{0.3, 0.2, 1}), pentagon},
      {"triangle_crossing_horizon", {0.1, 0, 0}, normalize(Vec3{1, 0.1, 0}), triangle},
  };
}

TEST(LambertPolygon, FormFactorMatchesQuadrature) {
  for (const Configuration& c : configurations()) {
    double closed = lambert_polygon_form_factor(c.x, c.n, c.polygon);
    double brute = brute_force_form_factor(c.x, c.n, c.polygon);
    EXPECT_GT(closed, 0.0) << c.name;
    EXPECT_LE(relative_difference(closed, brute), 2e-5) << c.name << " " << closed << " " << brute;
    // Winding does not matter for the form factor.
    std::vector<Vec3> reversed(c.polygon.rbegin(), c.polygon.rend());
    EXPECT_NEAR(lambert_polygon_form_factor(c.x, c.n, reversed), closed, 1e-14) << c.name;
  }
}

TEST(LambertPolygon, WholeHemisphereAndBelowTheHorizon) {
  // A huge square just above x covers almost the whole hemisphere: F -> 1.
  std::vector<Vec3> huge = {{-1e4, 1, -1e4}, {-1e4, 1, 1e4}, {1e4, 1, 1e4}, {1e4, 1, -1e4}};
  EXPECT_NEAR(lambert_polygon_form_factor({0, 0, 0}, {0, 1, 0}, huge), 1.0, 1e-7);
  // Entirely below the horizon: 0.
  EXPECT_EQ(lambert_polygon_form_factor({0, 2, 0}, {0, 1, 0}, huge), 0.0);
  // A disk-like 64-gon on the receiver's axis: F = R^2 / (R^2 + h^2) in the limit.
  std::vector<Vec3> ngon;
  for (int i = 0; i < 64; ++i) {
    double phi = 2 * kPi * i / 64;
    ngon.push_back(Vec3{std::cos(phi), 2.0, std::sin(phi)});
  }
  double polygon_area = 0.5 * 64 * std::sin(2 * kPi / 64);
  double equivalent_r2 = polygon_area / kPi;
  EXPECT_NEAR(lambert_polygon_form_factor({0, 0, 0}, {0, 1, 0}, ngon),
              equivalent_r2 / (equivalent_r2 + 4.0), 1e-4);
}

TEST(LambertPolygon, RadianceIsOneSided) {
  // Counter-clockwise seen from below: emits downwards.
  std::vector<Vec3> square = {{-0.5, 1, -0.5}, {0.5, 1, -0.5}, {0.5, 1, 0.5}, {-0.5, 1, 0.5}};
  Vec3 emission_normal = normalize(cross(square[1] - square[0], square[2] - square[0]));
  ASSERT_LT(emission_normal.y, 0);
  Rgb albedo{0.5, 0.6, 0.7}, le{2, 3, 4};
  Rgb below = lambert_polygon_radiance(albedo, le, {0, 0, 0}, {0, 1, 0}, square, emission_normal);
  double f = lambert_polygon_form_factor({0, 0, 0}, {0, 1, 0}, square);
  EXPECT_NEAR(below.x, 0.5 * 2 * f, 1e-15);
  EXPECT_NEAR(below.z, 0.7 * 4 * f, 1e-15);
  // Behind the light (above it, looking down at its back): nothing.
  EXPECT_TRUE(is_black(
      lambert_polygon_radiance(albedo, le, {0, 2, 0}, {0, -1, 0}, square, emission_normal)));
  // In its plane: nothing.
  EXPECT_TRUE(is_black(
      lambert_polygon_radiance(albedo, le, {2, 1, 0}, {-1, 0, 0}, square, emission_normal)));
}

}  // namespace
}  // namespace penumbra
