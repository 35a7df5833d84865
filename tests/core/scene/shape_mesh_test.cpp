// Triangulated shapes: counts, closedness, outward winding (volume by the divergence theorem),
// icosphere vertices on the sphere, OBJ parsing and its failures.

#include "core/scene/shape_mesh.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <stdexcept>
#include <utility>

namespace penumbra {
namespace {

// Each directed edge (a, b) of a closed, consistently wound mesh appears exactly once, and its
// reverse (b, a) exactly once too: every edge is shared by exactly two triangles.
void expect_closed_and_consistent(const TriangleMesh& mesh) {
  std::map<std::pair<uint32_t, uint32_t>, int> directed;
  for (size_t t = 0; t < mesh.indices.size(); t += 3)
    for (int k = 0; k < 3; ++k) ++directed[{mesh.indices[t + k], mesh.indices[t + (k + 1) % 3]}];
  for (const auto& [edge, count] : directed) {
    EXPECT_EQ(count, 1) << "edge " << edge.first << "-" << edge.second;
    auto reverse = directed.find({edge.second, edge.first});
    ASSERT_NE(reverse, directed.end()) << "open edge " << edge.first << "-" << edge.second;
    EXPECT_EQ(reverse->second, 1);
  }
}

// Signed volume enclosed by a closed mesh (sum of tetrahedra to the origin): positive when the
// triangles are wound counter-clockwise seen from outside.
double signed_volume(const TriangleMesh& mesh) {
  double volume = 0;
  for (size_t t = 0; t < mesh.indices.size(); t += 3) {
    const Vec3& a = mesh.positions[mesh.indices[t]];
    const Vec3& b = mesh.positions[mesh.indices[t + 1]];
    const Vec3& c = mesh.positions[mesh.indices[t + 2]];
    volume += dot(a, cross(b, c)) / 6.0;
  }
  return volume;
}

TEST(BoxMesh, HasTwelveTrianglesClosedAndOutward) {
  Vec3 min{-0.3, 0.4, -0.2}, max{0.5, 0.45, 0.7};
  TriangleMesh box = box_mesh(min, max);
  EXPECT_EQ(box.triangle_count(), 12u);
  EXPECT_EQ(box.positions.size(), 8u);
  expect_closed_and_consistent(box);
  Vec3 size = max - min;
  EXPECT_NEAR(signed_volume(box), size.x * size.y * size.z, 1e-15);
  // Every face normal points away from the centre.
  Vec3 centre = 0.5 * (min + max);
  for (size_t t = 0; t < box.indices.size(); t += 3) {
    const Vec3& a = box.positions[box.indices[t]];
    Vec3 normal =
        cross(box.positions[box.indices[t + 1]] - a, box.positions[box.indices[t + 2]] - a);
    EXPECT_GT(dot(normal, a - centre), 0);
  }
}

TEST(QuadMesh, TwoTrianglesCoveringTheParallelogram) {
  Vec3 origin{1, 2, 3}, edge1{2, 0, 0}, edge2{0.5, 0, 1};
  TriangleMesh quad = quad_mesh(origin, edge1, edge2);
  ASSERT_EQ(quad.triangle_count(), 2u);
  Vec3 expected_normal = cross(edge1, edge2);
  double area = 0;
  for (size_t t = 0; t < 6; t += 3) {
    const Vec3& a = quad.positions[quad.indices[t]];
    Vec3 n =
        cross(quad.positions[quad.indices[t + 1]] - a, quad.positions[quad.indices[t + 2]] - a);
    EXPECT_GT(dot(n, expected_normal), 0);  // wound like cross(edge1, edge2)
    area += 0.5 * length(n);
  }
  EXPECT_NEAR(area, length(expected_normal), 1e-14);
}

TEST(IcosphereMesh, CountsMatchAndVerticesLieOnTheSphere) {
  Vec3 centre{0.5, 0.3, -2};
  double radius = 0.3;
  for (int subdivisions = 0; subdivisions <= 5; ++subdivisions) {
    SCOPED_TRACE(subdivisions);
    TriangleMesh sphere = icosphere_mesh(centre, radius, subdivisions);
    EXPECT_EQ(sphere.triangle_count(), icosphere_triangle_count(subdivisions));
    EXPECT_EQ(sphere.positions.size(), icosphere_vertex_count(subdivisions));
    for (const Vec3& p : sphere.positions) EXPECT_NEAR(length(p - centre), radius, 1e-15);
    expect_closed_and_consistent(sphere);
    // Outward winding, and the volume approaches the ball's from below as it refines.
    Vec3 shift = -centre;
    TriangleMesh at_origin = sphere;
    for (Vec3& p : at_origin.positions) p += shift;
    double volume = signed_volume(at_origin);
    double ball = 4.0 / 3.0 * kPi * radius * radius * radius;
    EXPECT_GT(volume, 0);
    EXPECT_LT(volume, ball);
    if (subdivisions >= 3) {
      EXPECT_GT(volume, 0.99 * ball);
    }
  }
}

TEST(IcosphereMesh, TrianglesAreNearlyEqual) {
  // Midpoint subdivision keeps triangle areas within a small factor of each other (no slivers).
  TriangleMesh sphere = icosphere_mesh({0, 0, 0}, 1, 3);
  double smallest = 1e300, largest = 0;
  for (size_t t = 0; t < sphere.indices.size(); t += 3) {
    const Vec3& a = sphere.positions[sphere.indices[t]];
    double area = 0.5 * length(cross(sphere.positions[sphere.indices[t + 1]] - a,
                                     sphere.positions[sphere.indices[t + 2]] - a));
    smallest = std::min(smallest, area);
    largest = std::max(largest, area);
  }
  EXPECT_LT(largest / smallest, 2.0);
}

TEST(ObjMesh, ParsesTrianglesAndQuadsWithTransform) {
  std::string text =
      "# a unit square as a quad and a triangle beside it\n"
      "mtllib does-not-exist.mtl\n"
      "o square\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n"
      "o triangle\nv 2 0 0\nv 3 0 0\nv 2 1 0\nf 5 6 7\n"
      "o relative\nf -3 -2 -1\n";
  TriangleMesh mesh = obj_mesh(text, {2, 2, 2}, {0, 0, 5});
  EXPECT_EQ(mesh.positions.size(), 7u);
  EXPECT_EQ(mesh.triangle_count(), 2u + 1u + 1u);
  EXPECT_EQ(mesh.positions[2], Vec3(2, 2, 5));
  EXPECT_EQ(mesh.positions[4], Vec3(4, 0, 5));
  // The relative face (-3 -2 -1) names vertices 5, 6, 7.
  EXPECT_EQ(mesh.indices[9], 4u);
  EXPECT_EQ(mesh.indices[11], 6u);
}

TEST(ObjMesh, RefusesFilesWithoutTrianglesOrWithBadIndices) {
  EXPECT_THROW(obj_mesh("", {1, 1, 1}, {}), std::invalid_argument);
  EXPECT_THROW(obj_mesh("v 0 0 0\nv 1 0 0\nv 0 1 0\n", {1, 1, 1}, {}), std::invalid_argument);
  EXPECT_THROW(obj_mesh("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", {1, 1, 1}, {}),
               std::invalid_argument);
  EXPECT_THROW(obj_mesh("v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\n", {1, 1, 1}, {}),
               std::invalid_argument);
  try {
    obj_mesh("this is not an OBJ file\n", {1, 1, 1}, {});
    FAIL() << "accepted a file without triangles";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("no triangles"), std::string::npos);
  }
}

}  // namespace
}  // namespace penumbra
