// Peters' solid angle sampling of polygons (Peters 2021, Sec. 5): van Oosterom & Strackee's
// solid angle against quadrature, samples inside the polygon, tiny distant lights (Fig. 7).
// The distribution itself is chi-square tested through SolidAngleStrategy in
// tests/core/strategies/polygon_strategies_test.cpp.

#include "core/math/solid_angle_polygon.h"

#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "tests/support/polygon_test_util.h"

namespace penumbra {
namespace {

using polygon_test::hits_polygon;
using polygon_test::random_convex_polygon;
using polygon_test::random_unit_vector;
using polygon_test::uniform;

TEST(SolidAnglePolygon, SolidAngleMatchesQuadrature) {
  std::mt19937_64 rng(23);
  int checked = 0;
  for (int trial = 0; trial < 60; ++trial) {
    int n = 3 + int(uniform(rng) * 6);
    Vec3 center = random_unit_vector(rng) * (0.5 + 3 * uniform(rng));
    std::vector<Vec3> polygon =
        random_convex_polygon(rng, n, center, random_unit_vector(rng), 0.2 + uniform(rng));
    // Quadrature needs the point well off the polygon's plane.
    if (std::abs(dot(polygon_test::polygon_normal(polygon), polygon[0])) < 0.2) continue;
    double reference = polygon_test::brute_force_solid_angle(polygon, Vec3{}, 500);
    SolidAnglePolygonSampler sampler(polygon);
    EXPECT_NEAR(sampler.solid_angle(), reference, 1e-3 * reference) << "trial " << trial;
    EXPECT_NEAR(polygon_solid_angle(polygon), sampler.solid_angle(), 1e-12 * reference);
    EXPECT_NEAR(sampler.pdf() * sampler.solid_angle(), 1.0, 1e-15);
    ++checked;
  }
  EXPECT_GE(checked, 20);
}

TEST(SolidAnglePolygon, KnownSolidAngles) {
  // An octant: the spherical triangle of the three axes has solid angle 4 pi / 8.
  EXPECT_NEAR(triangle_solid_angle({1, 0, 0}, {0, 1, 0}, {0, 0, 1}), kPi / 2, 1e-15);
  // A square of side 2 at distance 1 subtends 2 pi / 3 (a cube face seen from the centre).
  std::vector<Vec3> face = {{-1, -1, 1}, {1, -1, 1}, {1, 1, 1}, {-1, 1, 1}};
  EXPECT_NEAR(SolidAnglePolygonSampler(face).solid_angle(), 2 * kPi / 3, 1e-14);
}

TEST(SolidAnglePolygon, SamplesLieInThePolygon) {
  std::mt19937_64 rng(29);
  for (int trial = 0; trial < 2000; ++trial) {
    int n = 3 + int(uniform(rng) * 6);
    Vec3 center = random_unit_vector(rng) * std::exp(std::log(0.01) + uniform(rng) * 9.0);
    std::vector<Vec3> polygon = random_convex_polygon(rng, n, center, random_unit_vector(rng),
                                                      length(center) * (0.01 + 3 * uniform(rng)));
    SolidAnglePolygonSampler sampler(polygon);
    if (sampler.solid_angle() == 0) continue;
    for (int k = 0; k < 8; ++k) {
      std::optional<Vec3> d = sampler.sample({uniform(rng), uniform(rng)});
      ASSERT_TRUE(d.has_value());
      ASSERT_TRUE(is_finite(*d));
      EXPECT_NEAR(length(*d), 1.0, 1e-12);
      EXPECT_TRUE(hits_polygon(polygon, *d, 1e-7)) << "trial " << trial;
    }
  }
}

TEST(SolidAnglePolygon, SubtriangleHasTheRequestedSolidAngle) {
  // Sample with u.y = 1 lands on the arc v1 v2'; the triangle (v0, v1, sample) then has solid
  // angle u.x times the triangle's (Peters Fig. 11b).
  std::mt19937_64 rng(31);
  for (int k = 0; k < 2000; ++k) {
    Vec3 a = random_unit_vector(rng), b = random_unit_vector(rng), c = random_unit_vector(rng);
    PreparedSphericalTriangle t = prepare_spherical_triangle(a, b, c);
    if (t.solid_angle < 1e-6) continue;
    double ux = uniform(rng);
    Vec3 end = sample_spherical_triangle(t, {ux, 1.0});
    double sub = triangle_solid_angle(t.v0, t.v1, end);
    EXPECT_NEAR(sub, ux * t.solid_angle, 1e-9 * (1 + t.solid_angle)) << k;
  }
}

// Fig. 7: a 1 cm and a 1 mm square light 40 m away.
TEST(SolidAnglePolygon, TinyDistantLightsStayFinite) {
  std::mt19937_64 rng(37);
  for (double side : {1e-2, 1e-3}) {
    for (int trial = 0; trial < 200; ++trial) {
      Vec3 toward = random_unit_vector(rng);
      std::vector<Vec3> light =
          random_convex_polygon(rng, 4, toward * 40.0, random_unit_vector(rng), side * 0.7071);
      SolidAnglePolygonSampler sampler(light);
      double expected = 0.5 * side * side * 4 / 1600.0;  // upper bound: area / distance^2
      ASSERT_TRUE(std::isfinite(sampler.solid_angle()));
      EXPECT_LE(sampler.solid_angle(), expected * 1.01);
      EXPECT_NEAR(sampler.solid_angle(), polygon_test::brute_force_solid_angle(light, Vec3{}, 20),
                  1e-6 * expected + 1e-9 * sampler.solid_angle());
      if (sampler.solid_angle() == 0) continue;
      for (int k = 0; k < 50; ++k) {
        std::optional<Vec3> d = sampler.sample({uniform(rng), uniform(rng)});
        ASSERT_TRUE(d.has_value());
        ASSERT_TRUE(is_finite(*d));
        EXPECT_TRUE(hits_polygon(light, *d, 1e-6)) << "side " << side << " trial " << trial;
      }
    }
  }
}

TEST(SolidAnglePolygon, DegeneratePolygonsGiveNoSample) {
  std::vector<Vec3> in_plane = {{1, 0, 0}, {2, 0, 0}, {2, 1, 0}, {1, 1, 0}};
  SolidAnglePolygonSampler sampler(in_plane);
  EXPECT_EQ(sampler.solid_angle(), 0.0);
  EXPECT_EQ(sampler.pdf(), 0.0);
  EXPECT_FALSE(sampler.sample({0.5, 0.5}).has_value());
  std::vector<Vec3> two = {{1, 0, 1}, {2, 0, 1}};
  EXPECT_FALSE(SolidAnglePolygonSampler(two).sample({0.5, 0.5}).has_value());
}

}  // namespace
}  // namespace penumbra
