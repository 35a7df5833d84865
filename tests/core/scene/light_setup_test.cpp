// Derived light fields (vertices, normal, area, centroid) and the degenerate-light checks, at
// several scales: tolerances are relative, so a 1 mm light and a 1 km light are judged alike.

#include "core/scene/light_setup.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace penumbra {
namespace {

void expect_vec_near(const Vec3& a, const Vec3& b, double tolerance) {
  EXPECT_NEAR(a.x, b.x, tolerance);
  EXPECT_NEAR(a.y, b.y, tolerance);
  EXPECT_NEAR(a.z, b.z, tolerance);
}

TEST(QuadLight, DerivedFieldsFollowTheContract) {
  // The Cornell-box light of the peer scene.
  Vec3 origin{-0.24, 1.98, -0.22}, edge1{0.47, 0, 0}, edge2{0, 0, 0.38};
  Light light = make_quad_light(origin, edge1, edge2, {68, 48, 16});
  ASSERT_EQ(light.vertices.size(), 4u);
  EXPECT_EQ(light.vertices[0], origin);
  EXPECT_EQ(light.vertices[1], origin + edge1);
  EXPECT_EQ(light.vertices[2], origin + edge1 + edge2);
  EXPECT_EQ(light.vertices[3], origin + edge2);
  expect_vec_near(light.normal, {0, -1, 0}, 1e-15);  // normalize(cross(edge1, edge2)): down
  EXPECT_NEAR(light.area, 0.47 * 0.38, 1e-15);
  expect_vec_near(light.centroid, {-0.005, 1.98, -0.03}, 1e-15);
}

TEST(QuadLight, ParallelogramAreaAndSwappedEdgesFlipTheNormal) {
  Light light = make_quad_light({0, 0, 0}, {2, 0, 0}, {1, 3, 0}, {1, 1, 1});
  EXPECT_NEAR(light.area, 6, 1e-14);
  expect_vec_near(light.normal, {0, 0, 1}, 1e-15);
  Light swapped = make_quad_light({0, 0, 0}, {1, 3, 0}, {2, 0, 0}, {1, 1, 1});
  expect_vec_near(swapped.normal, {0, 0, -1}, 1e-15);
}

TEST(QuadLight, RefusesDegenerateEdges) {
  EXPECT_THROW(make_quad_light({0, 0, 0}, {0, 0, 0}, {0, 0, 1}, {1, 1, 1}), std::invalid_argument);
  EXPECT_THROW(make_quad_light({0, 0, 0}, {1, 0, 0}, {-3, 0, 0}, {1, 1, 1}), std::invalid_argument);
  EXPECT_THROW(make_quad_light({0, 0, 0}, {1, 0, 0}, {0, 0, 1}, {1, -1, 1}), std::invalid_argument);
  EXPECT_THROW(make_quad_light({0, 0, 0}, {1, 0, 0}, {0, 0, NAN}, {1, 1, 1}),
               std::invalid_argument);
}

TEST(QuadLight, TinyAndHugeLightsAreAccepted) {
  // A 1 mm light 40 m away and a 1 km light: relative tolerances accept both.
  Light tiny = make_quad_light({40, 0, 0}, {1e-3, 0, 0}, {0, 1e-3, 0}, {1, 1, 1});
  EXPECT_NEAR(tiny.area, 1e-6, 1e-20);
  Light huge = make_quad_light({0, 0, 0}, {1e3, 0, 0}, {0, 1e3, 0}, {1, 1, 1});
  EXPECT_NEAR(huge.area, 1e6, 1e-6);
  // Nearly parallel edges at any scale are refused alike.
  for (double scale : {1e-4, 1.0, 1e4}) {
    EXPECT_THROW(make_quad_light({0, 0, 0}, {scale, 0, 0}, {scale, scale * 1e-12, 0}, {1, 1, 1}),
                 std::invalid_argument)
        << scale;
  }
}

TEST(PolygonLight, NormalAreaCentroidOfARegularHexagon) {
  // Counter-clockwise seen from +z, so it emits along +z; then tilted and moved.
  std::vector<Vec3> hexagon;
  double radius = 0.7;
  for (int k = 0; k < 6; ++k) {
    double angle = 2 * kPi * k / 6;
    hexagon.push_back({3 + radius * std::cos(angle), -1 + radius * std::sin(angle), 2});
  }
  Light light = make_polygon_light(hexagon, {5, 5, 5});
  expect_vec_near(light.normal, {0, 0, 1}, 1e-15);
  EXPECT_NEAR(light.area, 3 * std::sqrt(3.0) / 2 * radius * radius, 1e-14);
  expect_vec_near(light.centroid, {3, -1, 2}, 1e-14);
  EXPECT_EQ(light.vertices, hexagon);  // kept as given

  // Reversed order emits the other way.
  std::vector<Vec3> reversed(hexagon.rbegin(), hexagon.rend());
  expect_vec_near(make_polygon_light(reversed, {1, 1, 1}).normal, {0, 0, -1}, 1e-15);
}

TEST(PolygonLight, CentroidOfAnIrregularQuadrilateral) {
  // A trapezoid in the plane y = 2 with parallel sides 2 (z = 0) and 1 (z = 1).
  std::vector<Vec3> trapezoid = {{0, 2, 0}, {0.5, 2, 1}, {1.5, 2, 1}, {2, 2, 0}};
  Light light = make_polygon_light(trapezoid, {1, 1, 1});
  EXPECT_NEAR(light.area, 1.5, 1e-15);
  // Centroid height of a trapezoid: h (b + 2a) / (3 (a + b)) from the side b = 2 (z = 0).
  expect_vec_near(light.centroid, {1, 2, (2 + 2 * 1.0) / (3 * 3.0)}, 1e-15);
  expect_vec_near(light.normal, {0, 1, 0}, 1e-15);
}

TEST(PolygonLight, RefusesDegenerateShapes) {
  const Rgb white{1, 1, 1};
  // Too few vertices, coincident vertices, collinear, non-planar, non-convex, self-intersecting.
  EXPECT_THROW(make_polygon_light({{0, 0, 0}, {1, 0, 0}}, white), std::invalid_argument);
  EXPECT_THROW(make_polygon_light({{0, 0, 0}, {1, 0, 0}, {1, 0, 0}, {0, 1, 0}}, white),
               std::invalid_argument);
  EXPECT_THROW(make_polygon_light({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}}, white), std::invalid_argument);
  EXPECT_THROW(make_polygon_light({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0.01}}, white),
               std::invalid_argument);
  EXPECT_THROW(make_polygon_light({{0, 0, 0}, {2, 0, 0}, {2, 2, 0}, {1, 0.5, 0}, {0, 2, 0}}, white),
               std::invalid_argument);
  // A straight corner (vertex on an edge) is refused too: samplers need proper corners.
  EXPECT_THROW(make_polygon_light({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {2, 1, 0}, {0, 1, 0}}, white),
               std::invalid_argument);
  std::vector<Vec3> pentagram;
  for (int k = 0; k < 5; ++k) {
    double angle = 4 * kPi * k / 5;
    pentagram.push_back({std::cos(angle), std::sin(angle), 0});
  }
  EXPECT_THROW(make_polygon_light(pentagram, white), std::invalid_argument);
}

TEST(PolygonLight, PlanarityToleranceScalesWithSize) {
  // The same relative bend (1e-7 of the size) is accepted at every scale, 1e-5 refused.
  for (double scale : {1e-3, 1.0, 1e3}) {
    SCOPED_TRACE(scale);
    auto square = [&](double bend) {
      return std::vector<Vec3>{
          {0, 0, 0}, {scale, 0, 0}, {scale, scale, bend * scale}, {0, scale, 0}};
    };
    // Vertices 0, 1, 2 define the plane; vertex 3 lies off it by about bend * scale, against a
    // tolerance of 1e-6 times the extent (scale * sqrt(2)).
    EXPECT_NO_THROW(make_polygon_light(square(1e-7), {1, 1, 1}));
    EXPECT_THROW(make_polygon_light(square(1e-5), {1, 1, 1}), std::invalid_argument);
  }
}

TEST(DiskLight, DerivedFieldsAndChecks) {
  Light light = make_disk_light({1, 2, 3}, {0, 0, -4}, 0.5, {8, 8, 8});
  expect_vec_near(light.normal, {0, 0, -1}, 1e-15);
  EXPECT_NEAR(light.area, kPi * 0.25, 1e-15);
  EXPECT_EQ(light.centroid, Vec3(1, 2, 3));
  EXPECT_THROW(make_disk_light({0, 0, 0}, {0, 0, 0}, 1, {1, 1, 1}), std::invalid_argument);
  EXPECT_THROW(make_disk_light({0, 0, 0}, {0, 1, 0}, 0, {1, 1, 1}), std::invalid_argument);
  EXPECT_THROW(make_disk_light({0, 0, 0}, {0, 1, 0}, -1, {1, 1, 1}), std::invalid_argument);
}

TEST(LightProfile, GaussianNeedsPositiveSigmaAndAQuadOrDisk) {
  Light light = make_disk_light({0, 0, 0}, {0, 1, 0}, 1, {1, 1, 1});
  light.profile = ProfileType::Gaussian;
  light.sigma = 0.3;
  EXPECT_NO_THROW(derive_light_geometry(light));
  light.sigma = 0;
  EXPECT_THROW(derive_light_geometry(light), std::invalid_argument);
  Light polygon = make_polygon_light({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {1, 1, 1});
  polygon.profile = ProfileType::Gaussian;
  EXPECT_THROW(derive_light_geometry(polygon), std::invalid_argument);
}

}  // namespace
}  // namespace penumbra
