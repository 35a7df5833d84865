// LineQuery (BVH traversal) against the brute-force reference and against shadow rays;
// watertightness on closed meshes; self-occlusion, light-plane and degenerate cases.

#include "core/lines/line_query.h"

#include <gtest/gtest.h>
#include <pmmintrin.h>
#include <xmmintrin.h>

#include <cmath>
#include <random>
#include <vector>

#include "core/lines/occluder_meshes.h"
#include "core/lines/shadow_triangle.h"

namespace penumbra {
namespace {

using namespace occluder_meshes;

constexpr double kTolerance = 1e-6;

class Random {
 public:
  explicit Random(uint64_t seed) : rng_(seed) {}
  double uniform(double lo = 0, double hi = 1) { return lo + (hi - lo) * unit_(rng_); }
  Vec3 in_box(const Vec3& lo, const Vec3& hi) {
    return {uniform(lo.x, hi.x), uniform(lo.y, hi.y), uniform(lo.z, hi.z)};
  }
  Vec3 direction() {
    double z = uniform(-1, 1), phi = uniform(0, 2 * kPi), r = std::sqrt(1 - z * z);
    return {r * std::cos(phi), r * std::sin(phi), z};
  }
  // A unit vector within `angle` of unit vector `axis`, uniform in solid angle.
  Vec3 in_cone(const Vec3& axis, double angle) {
    Frame frame = Frame::from_normal(axis);
    double cos_theta = uniform(std::cos(angle), 1), phi = uniform(0, 2 * kPi);
    double sin_theta = std::sqrt(std::max(0.0, 1 - cos_theta * cos_theta));
    return frame.to_world({sin_theta * std::cos(phi), sin_theta * std::sin(phi), cos_theta});
  }
  size_t index(size_t n) { return static_cast<size_t>(uniform(0, static_cast<double>(n))) % n; }

 private:
  std::mt19937_64 rng_;
  std::uniform_real_distribution<double> unit_{0.0, 1.0};
};

void expect_same_intervals(const IntervalList& actual, const IntervalList& expected,
                           const char* what) {
  ASSERT_EQ(actual.size(), expected.size()) << what;
  for (size_t i = 0; i < actual.size(); ++i) {
    EXPECT_NEAR(actual[i].lo, expected[i].lo, kTolerance) << what << " piece " << i;
    EXPECT_NEAR(actual[i].hi, expected[i].hi, kTolerance) << what << " piece " << i;
  }
}

// Shadow ray against every triangle, rounded to float like the line query's occluders.
bool ray_blocked_brute_force(const TriangleMesh& mesh, const Vec3& x, const Vec3& p,
                             const ShadowTriangleTolerances& tolerances = {}) {
  for (size_t i = 0; i < mesh.triangle_count(); ++i) {
    std::optional<OccluderTriangle> occluder = OccluderTriangle::make(
        mesh.positions[mesh.indices[3 * i]], mesh.positions[mesh.indices[3 * i + 1]],
        mesh.positions[mesh.indices[3 * i + 2]]);
    if (occluder && segment_hits_triangle(x, p, tolerances.self_occlusion_epsilon,
                                          1 - tolerances.light_plane_epsilon, occluder->vertex(0),
                                          occluder->vertex(1), occluder->vertex(2)))
      return true;
  }
  return false;
}

IntervalList brute_force(const TriangleMesh& mesh, const Vec3& x, const Vec3& a, const Vec3& b) {
  IntervalList out;
  visible_intervals_brute_force(mesh.positions, mesh.indices, x, a, b, out);
  return out;
}

IntervalList query(const LineQuery& line_query, const Vec3& x, const Vec3& a, const Vec3& b) {
  IntervalList out;
  line_query.visible_intervals(x, a, b, out);
  return out;
}

void expect_finite_and_in_range(const IntervalList& list) {
  double length = list.visible_length();
  EXPECT_TRUE(std::isfinite(length));
  EXPECT_GE(length, 0.0);
  EXPECT_LE(length, 1.0);
  for (const Interval& piece : list) {
    EXPECT_TRUE(std::isfinite(piece.lo) && std::isfinite(piece.hi));
    EXPECT_GE(piece.lo, 0.0);
    EXPECT_LE(piece.hi, 1.0);
  }
}

// A quad (two triangles) from corner `origin` spanned by `u` and `v`.
TriangleMesh quad(const Vec3& origin, const Vec3& u, const Vec3& v) {
  TriangleMesh mesh;
  mesh.positions = {origin, origin + u, origin + u + v, origin + v};
  mesh.add_triangle(0, 1, 2);
  mesh.add_triangle(0, 2, 3);
  return mesh;
}

// A flat n x n grid of quads over [-half, half]^2 in the plane y = height.
TriangleMesh floor_grid(double half, double height, int n) {
  TriangleMesh mesh;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i)
      mesh.positions.push_back({-half + 2 * half * i / n, height, -half + 2 * half * j / n});
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      uint32_t i00 = j * (n + 1) + i, i10 = i00 + 1, i01 = i00 + n + 1, i11 = i01 + 1;
      mesh.add_triangle(i00, i10, i11);
      mesh.add_triangle(i00, i11, i01);
    }
  }
  return mesh;
}

TEST(LineQuery, StripOccluderMatchesClosedForm) {
  // x at the origin, segment from (-1,2,0) to (1,2,0); a strip at y = 1 over x in
  // [0.125, 0.375] projects from x (scale 2) onto x in [0.25, 0.75] of the segment: t in
  // [0.625, 0.875]. (Coordinates exact in float: occluders are rounded to float.)
  TriangleMesh mesh = quad({0.125, 1, -1}, {0.25, 0, 0}, {0, 0, 2});
  LineQuery line_query(mesh.positions, mesh.indices);
  IntervalList visible = query(line_query, {0, 0, 0}, {-1, 2, 0}, {1, 2, 0});
  ASSERT_EQ(visible.size(), 2u);
  EXPECT_NEAR(visible[0].lo, 0.0, 1e-15);
  EXPECT_NEAR(visible[0].hi, 0.625, 1e-15);
  EXPECT_NEAR(visible[1].lo, 0.875, 1e-15);
  EXPECT_NEAR(visible[1].hi, 1.0, 1e-15);
  EXPECT_NEAR(visible.visible_length(), 0.75, 1e-15);
}

TEST(LineQuery, BruteForceAgreesWithShadowRays) {
  Random random(1);
  TriangleMesh mesh = random_triangles_mesh(80, {-1, -1, -1}, {1, 1, 1}, 0.4, 2);
  int checked = 0;
  for (int trial = 0; trial < 300; ++trial) {
    Vec3 x = random.in_box({-1.5, -2.5, -1.5}, {1.5, -1.5, 1.5});
    Vec3 a = random.in_box({-1.5, 1.5, -1.5}, {1.5, 2.5, 1.5});
    Vec3 b = random.in_box({-1.5, 1.5, -1.5}, {1.5, 2.5, 1.5});
    IntervalList visible = brute_force(mesh, x, a, b);
    for (int i = 0; i < 64; ++i) {
      double t = random.uniform();
      // Skip points within 1e-9 of a piece boundary (the ray grazes an occluder's edge).
      bool near_boundary = false, inside = false;
      for (const Interval& piece : visible) {
        near_boundary |= std::fabs(t - piece.lo) < 1e-9 || std::fabs(t - piece.hi) < 1e-9;
        inside |= piece.lo < t && t < piece.hi;
      }
      if (near_boundary) continue;
      ++checked;
      EXPECT_EQ(!inside, ray_blocked_brute_force(mesh, x, a + t * (b - a))) << trial << " " << t;
    }
  }
  EXPECT_GT(checked, 19000);
}

void expect_matches_brute_force(const TriangleMesh& mesh, const LineQueryOptions& options,
                                int queries, uint64_t seed, double region) {
  LineQuery line_query(mesh.positions, mesh.indices, options);
  Random random(seed);
  int partially_visible = 0;
  for (int trial = 0; trial < queries; ++trial) {
    Vec3 x, a, b;
    if (trial % 2 == 0) {
      // Shading point below, segment above the geometry.
      x = random.in_box({-region, -2 * region, -region}, {region, -1.2 * region, region});
      a = random.in_box({-region, 1.2 * region, -region}, {region, 2 * region, region});
      b = a + 0.5 * region * random.direction();
    } else {
      // Anywhere, inside the geometry too.
      x = random.in_box({-region, -region, -region}, {region, region, region});
      a = random.in_box({-region, -region, -region}, {region, region, region});
      b = random.in_box({-region, -region, -region}, {region, region, region});
    }
    IntervalList expected;
    visible_intervals_brute_force(mesh.positions, mesh.indices, x, a, b, expected,
                                  options.tolerances);
    IntervalList actual = query(line_query, x, a, b);
    expect_same_intervals(actual, expected, "bvh vs brute force");
    if (::testing::Test::HasFailure()) {
      ADD_FAILURE() << "trial " << trial;
      return;
    }
    partially_visible += !expected.fully_occluded() && expected.visible_length() < 1;
  }
  // The configurations must exercise partial occlusion.
  EXPECT_GT(partially_visible, queries / 10);
}

TEST(LineQuery, MatchesBruteForceOnRandomTriangles) {
  TriangleMesh sparse = random_triangles_mesh(300, {-1, -1, -1}, {1, 1, 1}, 0.15, 3);
  TriangleMesh dense = random_triangles_mesh(5000, {-1, -1, -1}, {1, 1, 1}, 0.03, 4);
  expect_matches_brute_force(sparse, {}, 2000, 5, 1.0);
  expect_matches_brute_force(dense, {}, 1000, 6, 1.0);
}

TEST(LineQuery, MatchesBruteForceWithEveryBuildQualityAndLeafSize) {
  TriangleMesh mesh = random_triangles_mesh(2000, {-1, -1, -1}, {1, 1, 1}, 0.08, 7);
  for (LineQueryBuildQuality quality :
       {LineQueryBuildQuality::Low, LineQueryBuildQuality::Medium, LineQueryBuildQuality::High}) {
    for (unsigned leaf_size : {1u, 4u, 16u}) {
      LineQueryOptions options;
      options.build_quality = quality;
      options.max_leaf_size = leaf_size;
      expect_matches_brute_force(mesh, options, 300, 8 + leaf_size, 1.0);
    }
  }
}

TEST(LineQuery, SseAndAvxNodeTestsKeepTheSameChildren) {
  // The node test runs with AVX when the CPU has it, otherwise as two SSE halves doing the
  // same float operations per lane: the answers, and the culling itself (nodes, triangles and
  // cuts counted), must be the same bits either way. (On a CPU without AVX both builds take
  // the SSE path and the test still checks the brute force.)
  TriangleMesh mesh = random_triangles_mesh(4000, {-1, -1, -1}, {1, 1, 1}, 0.05, 11);
  mesh.append(floor_grid(1.5, -1.05, 8));
  LineQueryOptions sse_only;
  sse_only.allow_avx = false;
  LineQuery sse_query(mesh.positions, mesh.indices, sse_only);
  LineQuery default_query(mesh.positions, mesh.indices);
  EXPECT_FALSE(sse_query.uses_avx());
  Random random(12);
  LineQueryStats sse_stats, default_stats;
  int partially_visible = 0;
  for (int trial = 0; trial < 600; ++trial) {
    Vec3 x = random.in_box({-1, -1.05, -1}, {1, 0, 1});
    Vec3 a = random.in_box({-1, 1.2, -1}, {1, 2, 1});
    Vec3 b = a + 0.4 * random.direction();
    IntervalList sse_answer, default_answer;
    sse_query.visible_intervals(x, a, b, sse_answer, &sse_stats);
    default_query.visible_intervals(x, a, b, default_answer, &default_stats);
    ASSERT_EQ(sse_answer.size(), default_answer.size()) << trial;
    for (size_t i = 0; i < sse_answer.size(); ++i) {
      EXPECT_EQ(sse_answer[i].lo, default_answer[i].lo) << trial;
      EXPECT_EQ(sse_answer[i].hi, default_answer[i].hi) << trial;
    }
    if (trial % 10 == 0)
      expect_same_intervals(sse_answer, brute_force(mesh, x, a, b), "sse vs brute force");
    partially_visible += !sse_answer.fully_occluded() && sse_answer.visible_length() < 1;
  }
  EXPECT_EQ(sse_stats.nodes_visited, default_stats.nodes_visited);
  EXPECT_EQ(sse_stats.triangles_tested, default_stats.triangles_tested);
  EXPECT_EQ(sse_stats.cuts, default_stats.cuts);
  EXPECT_GT(partially_visible, 60);
}

TEST(LineQuery, MatchesBruteForceOnBoxesAndGridsWithIntegerQueries) {
  // Boxes on an integer lattice, a floor grid and a wall; shading points and segments on the
  // lattice too, so shadow planes pass exactly through vertices and along edges.
  TriangleMesh mesh = floor_grid(6, -3, 6);
  for (int i = -2; i <= 2; i += 2)
    for (int k = -2; k <= 2; k += 2)
      mesh.append(box_mesh({i - 0.5, -1.0 + (i + k) / 4.0, k - 0.5},
                           {i + 0.5, 0.0 + (i + k) / 4.0, k + 0.5}, 2));
  mesh.append(quad({-6, -3, -6}, {12, 0, 0}, {0, 9, 0}));
  LineQuery line_query(mesh.positions, mesh.indices);
  int partially_visible = 0, queries = 0;
  for (int xi = -3; xi <= 3; ++xi) {
    for (int xk = -3; xk <= 3; xk += 2) {
      for (int ai = -4; ai <= 4; ai += 2) {
        for (int bk = -4; bk <= 4; bk += 4) {
          Vec3 x(xi, -2, xk), a(ai, 4, -2), b(ai + 1, 4, bk);
          IntervalList expected = brute_force(mesh, x, a, b);
          expect_same_intervals(query(line_query, x, a, b), expected, "lattice");
          partially_visible += !expected.fully_occluded() && expected.visible_length() < 1;
          ++queries;
        }
      }
    }
  }
  EXPECT_GT(partially_visible, queries / 10);
}

// Every ray from x towards the segment passes through the inscribed ball of the closed mesh:
// nothing of the segment may stay visible, not even a sliver at a seam.
TEST(LineQuery, ClosedIcosphereOccludesEverythingExactly) {
  Random random(21);
  int configurations = 0;
  for (int mesh_index = 0; mesh_index < 12; ++mesh_index) {
    Vec3 center = random.in_box({-3, -3, -3}, {3, 3, 3});
    double radius = random.uniform(0.5, 2);
    TriangleMesh mesh = icosphere_mesh(center, radius, 1 + mesh_index % 3);
    // Inradius: the nearest face plane to the centre.
    double inradius = radius;
    for (size_t i = 0; i < mesh.triangle_count(); ++i) {
      const Vec3& v0 = mesh.positions[mesh.indices[3 * i]];
      Vec3 n = normalize(cross(mesh.positions[mesh.indices[3 * i + 1]] - v0,
                               mesh.positions[mesh.indices[3 * i + 2]] - v0));
      inradius = std::min(inradius, std::fabs(dot(v0 - center, n)));
    }
    LineQuery line_query(mesh.positions, mesh.indices);
    for (int trial = 0; trial < 350; ++trial) {
      double distance = radius * random.uniform(1.5, 6);
      Vec3 x = center + distance * random.direction();
      Vec3 axis = normalize(center - x);
      double cone = 0.98 * std::asin(inradius / distance);
      double beyond = distance + radius;
      Vec3 a, b;
      int kind = trial % 3;
      if (kind == 0) {
        // Random directions in the cone.
        a = x + beyond * random.uniform(1.05, 3) * random.in_cone(axis, cone);
        b = x + beyond * random.uniform(1.05, 3) * random.in_cone(axis, cone);
      } else {
        // Through mesh vertices (kind 1) or edge midpoints (kind 2) inside the cone: the shadow
        // plane then passes through vertices and along edges.
        std::vector<Vec3> targets;
        for (size_t i = 0; i < mesh.triangle_count(); ++i) {
          for (int k = 0; k < 3; ++k) {
            Vec3 p = mesh.positions[mesh.indices[3 * i + k]];
            if (kind == 2) p = 0.5 * (p + mesh.positions[mesh.indices[3 * i + (k + 1) % 3]]);
            if (std::acos(std::min(1.0, dot(normalize(p - x), axis))) < cone) targets.push_back(p);
          }
        }
        if (targets.size() < 2) continue;
        Vec3 p = targets[random.index(targets.size())], q = targets[random.index(targets.size())];
        a = x + random.uniform(1.05, 3) * beyond / length(p - x) * (p - x);
        b = x + random.uniform(1.05, 3) * beyond / length(q - x) * (q - x);
      }
      IntervalList visible = query(line_query, x, a, b);
      EXPECT_TRUE(visible.fully_occluded())
          << "mesh " << mesh_index << " trial " << trial << " visible " << visible.visible_length()
          << " in " << visible.size() << " pieces";
      EXPECT_EQ(visible.visible_length(), 0.0);
      if (trial % 8 == 0) {
        EXPECT_TRUE(brute_force(mesh, x, a, b).fully_occluded());
      }
      ++configurations;
    }
  }
  EXPECT_GT(configurations, 3500);
}

TEST(LineQuery, ClosedBoxOccludesEverythingOnLatticePlanes) {
  // Box [-2,2]^3 with unit faces; x and the segment on a half-integer lattice on either side,
  // so shadow planes run exactly through vertices and along edges of the box.
  TriangleMesh mesh = box_mesh({-2, -2, -2}, {2, 2, 2}, 4);
  LineQuery line_query(mesh.positions, mesh.indices);
  const double values[] = {-1, -0.5, 0, 0.5, 1};
  int configurations = 0;
  for (int axis = 0; axis < 3; ++axis) {
    auto point = [&](double u, double along, double v) {
      Vec3 p;
      p[axis] = along;
      p[(axis + 1) % 3] = u;
      p[(axis + 2) % 3] = v;
      return p;
    };
    for (double xu : values)
      for (double xv : values)
        for (double au : values)
          for (double av : values)
            for (double bu : values)
              for (double bv : values) {
                Vec3 x = point(xu, -6, xv), a = point(au, 6, av), b = point(bu, 6, bv);
                IntervalList visible = query(line_query, x, a, b);
                EXPECT_TRUE(visible.fully_occluded()) << x.x << " " << x.y << " " << x.z;
                ++configurations;
              }
  }
  EXPECT_EQ(configurations, 3 * 15625);
  // The brute force agrees on a sample.
  EXPECT_TRUE(brute_force(mesh, {0, -6, 0}, {0, 6, 0}, {1, 6, 1}).fully_occluded());
  EXPECT_TRUE(brute_force(mesh, {1, -6, 1}, {-1, 6, -1}, {1, 6, -1}).fully_occluded());
}

TEST(LineQuery, TrianglesSharingAnEdgeWithTheShadowTriangle) {
  const Vec3 x(0, 0, 0), a(-1, 1, 0), b(1, 1, 0);
  // Sharing the segment, in the light's plane beyond it: does not occlude.
  TriangleMesh on_segment;
  on_segment.positions = {a, b, {0, 1, 1}};
  on_segment.add_triangle(0, 1, 2);
  // Sharing the edge x-a: its crossing is radial from x, a cut of zero length.
  TriangleMesh on_side;
  on_side.positions = {x, a, {0, 0.5, 1}};
  on_side.add_triangle(0, 1, 2);
  // The shadow triangle itself: coplanar, does not occlude.
  TriangleMesh itself;
  itself.positions = {x, a, b};
  itself.add_triangle(0, 1, 2);
  for (const TriangleMesh* mesh : {&on_segment, &on_side, &itself}) {
    LineQuery line_query(mesh->positions, mesh->indices);
    IntervalList visible = query(line_query, x, a, b);
    ASSERT_EQ(visible.size(), 1u);
    EXPECT_EQ(visible.visible_length(), 1.0);
    expect_same_intervals(visible, brute_force(*mesh, x, a, b), "shared edge");
  }
  // An edge lying in the shadow plane between x and the segment (the triangle touches the
  // shadow triangle along it) cuts what it covers, as the shared edge of a closed mesh must:
  // from x, the edge (-0.25..0.25 at y = 0.5) covers x in [-0.5, 0.5] of the segment.
  TriangleMesh touching;
  touching.positions = {{-0.25, 0.5, 0}, {0.25, 0.5, 0}, {0, 0.5, 1}};
  touching.add_triangle(0, 1, 2);
  LineQuery line_query(touching.positions, touching.indices);
  IntervalList visible = query(line_query, x, a, b);
  ASSERT_EQ(visible.size(), 2u);
  EXPECT_NEAR(visible[0].hi, 0.25, 1e-15);
  EXPECT_NEAR(visible[1].lo, 0.75, 1e-15);
}

TEST(LineQuery, SurfaceUnderTheShadingPointDoesNotOcclude) {
  Random random(31);
  // Floor grid at y = 0; x on it (random points, grid vertices and grid edges).
  TriangleMesh floor = floor_grid(4, 0, 8);
  LineQuery floor_query(floor.positions, floor.indices);
  for (int trial = 0; trial < 2000; ++trial) {
    Vec3 x;
    if (trial % 3 == 0) x = {random.uniform(-3, 3), 0, random.uniform(-3, 3)};
    if (trial % 3 == 1)
      x = {std::round(random.uniform(-3, 3)), 0, std::round(random.uniform(-3, 3))};
    if (trial % 3 == 2) x = {std::round(random.uniform(-3, 3)), 0, random.uniform(-3, 3)};
    Vec3 a = random.in_box({-3, 1, -3}, {3, 3, 3});
    // Half the segments reach below the floor's plane (beyond the horizon).
    Vec3 b = random.in_box({-3, trial % 2 ? -1.0 : 1.0, -3}, {3, 3, 3});
    IntervalList visible = query(floor_query, x, a, b);
    ASSERT_EQ(visible.size(), 1u) << trial;
    EXPECT_EQ(visible.visible_length(), 1.0) << trial;
  }
  // x on an icosphere's face (rounded to float, as a ray hit would be), the segment above it.
  TriangleMesh sphere = icosphere_mesh({0.5, -0.25, 1}, 1.5, 3);
  LineQuery sphere_query(sphere.positions, sphere.indices);
  for (int trial = 0; trial < 2000; ++trial) {
    size_t face = random.index(sphere.triangle_count());
    const Vec3& v0 = sphere.positions[sphere.indices[3 * face]];
    const Vec3& v1 = sphere.positions[sphere.indices[3 * face + 1]];
    const Vec3& v2 = sphere.positions[sphere.indices[3 * face + 2]];
    double u = random.uniform(), v = random.uniform();
    if (u + v > 1) {
      u = 1 - u;
      v = 1 - v;
    }
    Vec3 x = v0 + u * (v1 - v0) + v * (v2 - v0);
    if (trial % 2) x = {static_cast<float>(x.x), static_cast<float>(x.y), static_cast<float>(x.z)};
    Vec3 n = normalize(cross(v1 - v0, v2 - v0));
    if (dot(n, v0 - Vec3(0.5, -0.25, 1)) < 0) n = -n;
    Vec3 a = x + 3 * random.in_cone(n, 0.5), b = x + 3 * random.in_cone(n, 0.5);
    IntervalList visible = query(sphere_query, x, a, b);
    EXPECT_GE(visible.visible_length(), 1 - 1e-12) << trial;
  }
}

TEST(LineQuery, OccludersInTheLightsPlaneDoNotCount) {
  // A ceiling at y = 2 with the segment lying in it: the ceiling does not occlude.
  TriangleMesh ceiling = floor_grid(3, 2, 6);
  ceiling.append(box_mesh({-0.5, 0.5, -0.5}, {0.5, 1.0, 0.5}));  // a real occluder
  LineQuery line_query(ceiling.positions, ceiling.indices);
  Random random(41);
  for (int trial = 0; trial < 1000; ++trial) {
    Vec3 x = random.in_box({-2, -1, -2}, {2, 0, 2});
    Vec3 a = random.in_box({-2, 2, -2}, {2, 2, 2});
    Vec3 b = random.in_box({-2, 2, -2}, {2, 2, 2});
    IntervalList visible = query(line_query, x, a, b);
    // Only the box occludes: compare with the box alone.
    TriangleMesh box_only = box_mesh({-0.5, 0.5, -0.5}, {0.5, 1.0, 0.5});
    expect_same_intervals(visible, brute_force(box_only, x, a, b), "ceiling");
  }
}

TEST(LineQuery, DegenerateInputsGiveFiniteAnswers) {
  TriangleMesh mesh = quad({-1, 1, -1}, {2, 0, 0}, {0, 0, 2});  // blocks the axis x = z = 0
  // Zero-area occluders: collinear vertices and a repeated vertex, crossing everything.
  mesh.positions.insert(mesh.positions.end(), {{3, -5, 3}, {3, 5, 3}, {3, 10, 3}, {4, 0, 4}});
  mesh.add_triangle(4, 5, 6);
  mesh.add_triangle(4, 7, 7);
  LineQuery line_query(mesh.positions, mesh.indices);
  EXPECT_EQ(line_query.triangle_count(), 2u);  // the zero-area ones were dropped

  // a == b: one ray. Blocked on the axis, free beside the quad.
  EXPECT_TRUE(query(line_query, {0, 0, 0}, {0, 2, 0}, {0, 2, 0}).fully_occluded());
  EXPECT_EQ(query(line_query, {5, 0, 0}, {5, 2, 0}, {5, 2, 0}).visible_length(), 1.0);
  // x on the segment's line, x == a.
  EXPECT_TRUE(query(line_query, {0, 0, 0}, {0, 2, 0}, {0, 3, 0}).fully_occluded());
  expect_finite_and_in_range(query(line_query, {0, 2, 0}, {0, 2, 0}, {1, 2, 0}));
  // Nearly degenerate: a tiny segment far away.
  expect_finite_and_in_range(query(line_query, {0, 0, 0}, {0, 2, 0}, {1e-12, 2, 0}));
  // The zero-area occluders cross this shadow triangle but cut nothing.
  EXPECT_EQ(query(line_query, {3, -1, 0}, {3, 2, 2}, {3, 2, 6}).visible_length(), 1.0);
  // Coplanar occluder: a triangle in the shadow plane z = 0.
  TriangleMesh coplanar;
  coplanar.positions = {{-0.5, 0.5, 0}, {0.5, 0.5, 0}, {0, 1, 0}};
  coplanar.add_triangle(0, 1, 2);
  LineQuery coplanar_query(coplanar.positions, coplanar.indices);
  EXPECT_EQ(query(coplanar_query, {0, 0, 0}, {-1, 2, 0}, {1, 2, 0}).visible_length(), 1.0);
  // Non-finite input: nothing visible, no crash.
  const double nan = std::nan(""), inf = INFINITY;
  EXPECT_TRUE(query(line_query, {nan, 0, 0}, {0, 2, 0}, {1, 2, 0}).fully_occluded());
  EXPECT_TRUE(query(line_query, {0, 0, 0}, {inf, 2, 0}, {1, 2, 0}).fully_occluded());
  // Extreme scales stay finite.
  TriangleMesh huge = random_triangles_mesh(200, {-1e6, -1e6, -1e6}, {1e6, 1e6, 1e6}, 2e5, 9);
  TriangleMesh tiny =
      random_triangles_mesh(200, {-1e-6, -1e-6, -1e-6}, {1e-6, 1e-6, 1e-6}, 2e-7, 9);
  Random random(51);
  for (const TriangleMesh* m : {&huge, &tiny}) {
    LineQuery q(m->positions, m->indices);
    double s = m == &huge ? 1e6 : 1e-6;
    for (int trial = 0; trial < 200; ++trial) {
      Vec3 x = s * random.in_box({-2, -2, -2}, {2, 2, 2});
      Vec3 a = s * random.in_box({-2, -2, -2}, {2, 2, 2}),
           b = s * random.in_box({-2, -2, -2}, {2, 2, 2});
      IntervalList visible = query(q, x, a, b);
      expect_finite_and_in_range(visible);
      expect_same_intervals(visible, brute_force(*m, x, a, b), "extreme scale");
    }
  }
  // No occluders at all.
  LineQuery empty(std::vector<Vec3>{}, std::vector<uint32_t>{});
  EXPECT_EQ(query(empty, {0, 0, 0}, {0, 2, 0}, {1, 2, 0}).visible_length(), 1.0);
}

TEST(LineQuery, ManyCoincidentTrianglesBuildAndQuery) {
  // 5000 copies of one triangle (no split helps the builder) plus copies of a quad: the tree
  // stays within the traversal's bounds and the answer matches the brute force.
  TriangleMesh mesh;
  mesh.positions = {{-0.5, 1, -0.5}, {0.5, 1, -0.5}, {0, 1, 0.5}};
  for (int i = 0; i < 5000; ++i) mesh.add_triangle(0, 1, 2);
  for (int i = 0; i < 100; ++i) mesh.append(quad({-2, 1.5, -2}, {1, 0, 0}, {0, 0, 1}));
  LineQuery line_query(mesh.positions, mesh.indices);
  EXPECT_EQ(line_query.triangle_count(), 5200u);
  Random random(91);
  for (int trial = 0; trial < 50; ++trial) {
    Vec3 x = random.in_box({-1, -1, -1}, {1, 0, 1});
    Vec3 a = random.in_box({-2, 2, -2}, {2, 2.5, 2}), b = random.in_box({-2, 2, -2}, {2, 2.5, 2});
    expect_same_intervals(query(line_query, x, a, b), brute_force(mesh, x, a, b), "coincident");
  }
}

TEST(LineQuery, ScalingTheSceneByPowersOfTwoGivesTheSameBits) {
  // Render threads run with flush-to-zero and denormals-are-zero: so does this test, down to
  // scales where squared lengths would be float denormals.
  struct FlushDenormalsScope {
    unsigned saved = _mm_getcsr();
    FlushDenormalsScope() {
      _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
      _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
    }
    ~FlushDenormalsScope() { _mm_setcsr(saved); }
  } flush_denormals;
  TriangleMesh mesh = random_triangles_mesh(1000, {-1, -1, -1}, {1, 1, 1}, 0.1, 61);
  LineQuery unit_query(mesh.positions, mesh.indices);
  for (double scale : {1024.0, 1.0 / 1024, std::ldexp(1.0, -66), std::ldexp(1.0, 20)}) {
    TriangleMesh scaled = mesh;
    for (Vec3& p : scaled.positions) p = scale * p;
    LineQuery scaled_query(scaled.positions, scaled.indices);
    Random random(62);
    // The culling scales too: the same triangles are tested.
    LineQueryStats unit_stats, scaled_stats;
    for (int trial = 0; trial < 300; ++trial) {
      Vec3 x = random.in_box({-1, -2, -1}, {1, -1, 1});
      Vec3 a = random.in_box({-1, 1, -1}, {1, 2, 1}), b = random.in_box({-1, 1, -1}, {1, 2, 1});
      IntervalList expected, actual;
      unit_query.visible_intervals(x, a, b, expected, &unit_stats);
      scaled_query.visible_intervals(scale * x, scale * a, scale * b, actual, &scaled_stats);
      ASSERT_EQ(actual.size(), expected.size());
      for (size_t i = 0; i < actual.size(); ++i) {
        EXPECT_EQ(actual[i].lo, expected[i].lo);
        EXPECT_EQ(actual[i].hi, expected[i].hi);
      }
    }
    EXPECT_EQ(scaled_stats.triangles_tested, unit_stats.triangles_tested) << scale;
  }
}

TEST(LineQuery, TraversalCullsMostTriangles) {
  // Thin shadow triangles through 20k small triangles: the BVH must test far fewer triangles
  // than the brute force, and find the same answer.
  TriangleMesh mesh = random_triangles_mesh(20000, {-1, -1, -1}, {1, 1, 1}, 0.01, 71);
  LineQuery line_query(mesh.positions, mesh.indices);
  Random random(72);
  LineQueryStats stats;
  const int queries = 200;
  for (int trial = 0; trial < queries; ++trial) {
    Vec3 x = random.in_box({-1, -2, -1}, {1, -1.5, 1});
    Vec3 a = random.in_box({-1, 1.5, -1}, {1, 2, 1});
    Vec3 b = a + 0.2 * random.direction();
    IntervalList actual;
    line_query.visible_intervals(x, a, b, actual, &stats);
    if (trial % 20 == 0) {
      expect_same_intervals(actual, brute_force(mesh, x, a, b), "culling");
    }
  }
  double tested_per_query = static_cast<double>(stats.triangles_tested) / queries;
  EXPECT_LT(tested_per_query, 0.05 * mesh.triangle_count());
  EXPECT_GT(stats.cuts, 0u);
}

// The same intervals bit for bit (the BVH's culling is conservative, the leaves run the same
// exact test as the brute force, and subtracting closed cuts does not depend on their order).
void expect_identical_intervals(const IntervalList& actual, const IntervalList& expected,
                                const char* what) {
  ASSERT_EQ(actual.size(), expected.size()) << what;
  for (size_t i = 0; i < actual.size(); ++i) {
    EXPECT_EQ(actual[i].lo, expected[i].lo) << what << " piece " << i;
    EXPECT_EQ(actual[i].hi, expected[i].hi) << what << " piece " << i;
  }
}

// Rotates the mesh about the origin (the same vertex gives the same bits: closed stays closed).
TriangleMesh rotated(TriangleMesh mesh, const Vec3& axis, double angle) {
  const Frame frame = Frame::from_normal(normalize(axis));
  const double c = std::cos(angle), s = std::sin(angle);
  for (Vec3& p : mesh.positions) {
    Vec3 local = frame.to_local(p);
    p = frame.to_world({c * local.x - s * local.y, s * local.x + c * local.y, local.z});
  }
  return mesh;
}

// A soup meant to break conservative culling: long thin slanted bars (split into pieces by the
// build), slivers (one vertex within ~1e-7 of the opposite edge), a huge triangle through the
// query region, tiny triangles, and a slanted closed box.
TriangleMesh adversarial_mesh(Random& random) {
  TriangleMesh mesh;
  for (int i = 0; i < 40; ++i) {
    // A bar: two triangles 3 long and 0.01 wide, in a random slanted direction.
    Vec3 center = random.in_box({-1, -1, -1}, {1, 1, 1});
    Vec3 along = 1.5 * random.direction(),
         across = 0.005 * normalize(cross(along, random.direction()));
    uint32_t base = static_cast<uint32_t>(mesh.positions.size());
    mesh.positions.insert(mesh.positions.end(), {center - along - across, center + along - across,
                                                 center + along + across, center - along + across});
    mesh.add_triangle(base, base + 1, base + 2);
    mesh.add_triangle(base, base + 2, base + 3);
  }
  for (int i = 0; i < 40; ++i) {
    // A sliver: the third vertex ~1e-7 off the segment between the first two.
    Vec3 p = random.in_box({-1, -1, -1}, {1, 1, 1}), q = p + random.direction();
    Vec3 r = p + random.uniform(0.1, 0.9) * (q - p) + 1e-7 * random.direction();
    uint32_t base = static_cast<uint32_t>(mesh.positions.size());
    mesh.positions.insert(mesh.positions.end(), {p, q, r});
    mesh.add_triangle(base, base + 1, base + 2);
  }
  {
    // A huge triangle through the region, and tiny ones.
    uint32_t base = static_cast<uint32_t>(mesh.positions.size());
    mesh.positions.insert(mesh.positions.end(),
                          {{-1e4, 0.3, -1e4}, {1e4, -0.2, -1e4}, {0, 0.1, 2e4}});
    mesh.add_triangle(base, base + 1, base + 2);
    mesh.append(random_triangles_mesh(200, {-1, -1, -1}, {1, 1, 1}, 1e-5, 5));
  }
  mesh.append(rotated(box_mesh({-0.3, -0.3, -0.3}, {0.3, 0.3, 0.3}, 3), {1, 2, 3}, 0.7));
  return mesh;
}

TEST(LineQuery, AdversarialPlanesThroughVerticesAndEdgesMatchBruteForceExactly) {
  Random random(101);
  TriangleMesh mesh = adversarial_mesh(random);
  // Every build (pre-split or not, every quality, small and large leaves) against the brute
  // force, on shadow triangles whose planes pass through vertices and along edges.
  std::vector<LineQueryOptions> builds;
  for (bool split : {true, false}) {
    for (LineQueryBuildQuality quality :
         {LineQueryBuildQuality::Low, LineQueryBuildQuality::Medium, LineQueryBuildQuality::High}) {
      LineQueryOptions options;
      options.split_long_triangles = split;
      options.build_quality = quality;
      options.max_leaf_size = quality == LineQueryBuildQuality::Low ? 1 : 4;
      builds.push_back(options);
    }
  }
  std::vector<LineQuery> queries;
  for (const LineQueryOptions& options : builds)
    queries.emplace_back(mesh.positions, mesh.indices, options);
  auto vertex = [&](size_t triangle, int k) {
    return mesh.positions[mesh.indices[3 * triangle + k]];
  };
  int partially_visible = 0;
  const int trials = 900;
  for (int trial = 0; trial < trials; ++trial) {
    Vec3 x = random.in_box({-1.5, -1.5, -1.5}, {1.5, 1.5, 1.5});
    Vec3 a, b;
    const size_t t = random.index(mesh.triangle_count());
    const int k = static_cast<int>(random.index(3));
    switch (trial % 5) {
      case 0:  // random
        a = random.in_box({-2, -2, -2}, {2, 2, 2});
        b = random.in_box({-2, -2, -2}, {2, 2, 2});
        break;
      case 1: {  // the shadow plane through a vertex
        Vec3 v = vertex(t, k);
        a = x + random.uniform(1.2, 3) * (random.in_box({-1, -1, -1}, {1, 1, 1}) - x);
        b = x + random.uniform(1.2, 3) * (v - x) + random.uniform(-0.5, 0.5) * (a - x);
        break;
      }
      case 2: {  // the shadow plane along an edge, the segment's ends behind its vertices
        Vec3 v0 = vertex(t, k), v1 = vertex(t, (k + 1) % 3);
        a = x + random.uniform(1.2, 3) * (v0 - x);
        b = x + random.uniform(1.2, 3) * (v1 - x);
        break;
      }
      case 3: {  // x on a vertex of one triangle, the segment anywhere
        x = vertex(t, k);
        a = random.in_box({-2, -2, -2}, {2, 2, 2});
        b = random.in_box({-2, -2, -2}, {2, 2, 2});
        break;
      }
      default: {  // x on an edge, the segment behind another triangle's vertices
        x = 0.5 * (vertex(t, k) + vertex(t, (k + 1) % 3));
        const size_t u = random.index(mesh.triangle_count());
        a = x + random.uniform(1.2, 3) * (vertex(u, 0) - x);
        b = x + random.uniform(1.2, 3) * (vertex(u, 1) - x);
        break;
      }
    }
    IntervalList expected;
    visible_intervals_brute_force(mesh.positions, mesh.indices, x, a, b, expected);
    for (size_t q = 0; q < queries.size(); ++q) {
      IntervalList actual;
      queries[q].visible_intervals(x, a, b, actual);
      expect_identical_intervals(actual, expected, "adversarial");
      if (::testing::Test::HasFailure()) {
        ADD_FAILURE() << "trial " << trial << " build " << q;
        return;
      }
    }
    partially_visible += !expected.fully_occluded() && expected.visible_length() < 1;
  }
  EXPECT_GT(partially_visible, trials / 5);
}

TEST(LineQuery, PreSplitTestsFewerTrianglesAndGivesTheSameBits) {
  // Two lattices of long bars rotated about the vertical (no bar along an axis) over a floor:
  // without pre-splitting every bar's box spans the lattice's width.
  TriangleMesh mesh = floor_grid(3, 0, 2);
  for (int layer = 0; layer < 2; ++layer) {
    TriangleMesh lattice;
    for (int i = -5; i <= 5; ++i) {
      lattice.append(box_mesh({-2.0, 0.5 + 0.4 * layer, 0.3 * i - 0.02},
                              {2.0, 0.52 + 0.4 * layer, 0.3 * i + 0.02}));
      lattice.append(box_mesh({0.3 * i - 0.02, 0.5 + 0.4 * layer, -2.0},
                              {0.3 * i + 0.02, 0.52 + 0.4 * layer, 2.0}));
    }
    mesh.append(rotated(lattice, {0, 1, 0}, layer == 0 ? 0.35 : -0.6));
  }
  LineQueryOptions whole;
  whole.split_long_triangles = false;
  LineQuery split_query(mesh.positions, mesh.indices);
  LineQuery whole_query(mesh.positions, mesh.indices, whole);
  Random random(111);
  LineQueryStats split_stats, whole_stats;
  for (int trial = 0; trial < 400; ++trial) {
    Vec3 x = {random.uniform(-2, 2), 0, random.uniform(-2, 2)};
    Vec3 a = random.in_box({-0.5, 2.2, -0.5}, {0.5, 2.2, 0.5});
    Vec3 b = a + Vec3(random.uniform(0.2, 0.5), 0, random.uniform(-0.2, 0.2));
    IntervalList split_answer, whole_answer;
    split_query.visible_intervals(x, a, b, split_answer, &split_stats);
    whole_query.visible_intervals(x, a, b, whole_answer, &whole_stats);
    expect_identical_intervals(split_answer, whole_answer, "pre-split vs whole");
    if (trial % 20 == 0)
      expect_identical_intervals(split_answer, brute_force(mesh, x, a, b),
                                 "pre-split vs brute force");
  }
  EXPECT_GT(split_stats.cuts, 400u);
  EXPECT_LT(split_stats.triangles_tested, whole_stats.triangles_tested / 2);
}

TEST(LineQuery, SlantedClosedMeshesOccludeEverythingWhenPreSplit) {
  // Closed meshes whose faces are long and slanted (so the build splits them): a long rotated
  // box and a rotated UV sphere squashed into a disc. From x the segment lies behind the mesh's
  // core: nothing may stay visible.
  Random random(121);
  int configurations = 0;
  for (int mesh_index = 0; mesh_index < 4; ++mesh_index) {
    TriangleMesh mesh;
    if (mesh_index % 2 == 0) {
      mesh = rotated(box_mesh({-3, -0.2, -0.2}, {3, 0.2, 0.2}, 1 + mesh_index), random.direction(),
                     random.uniform(0.3, 1.2));
    } else {
      mesh = uv_sphere_mesh({0, 0, 0}, 1, 12, 24);
      for (Vec3& p : mesh.positions) p = {3 * p.x, 0.3 * p.y, 3 * p.z};
      mesh = rotated(mesh, random.direction(), random.uniform(0.3, 1.2));
    }
    LineQuery line_query(mesh.positions, mesh.indices);
    for (int trial = 0; trial < 300; ++trial) {
      // Through a point near the centre (inside the mesh's core, radius 0.1) along a random
      // direction, a thin shadow triangle: x in front, the segment behind.
      Vec3 core = 0.1 * random.uniform() * random.direction();
      Vec3 direction = random.direction();
      Vec3 x = core + random.uniform(4, 8) * direction;
      Vec3 side = normalize(cross(direction, random.direction()));
      Vec3 behind = core - random.uniform(4, 8) * direction;
      // Half-width so small that every ray from x to the segment passes within 0.1 + 0.05 of
      // the centre (inside both meshes).
      double half = 0.04 * length(behind - x) / length(core - x);
      Vec3 a = behind - half * side, b = behind + half * side;
      IntervalList visible = query(line_query, x, a, b);
      EXPECT_TRUE(visible.fully_occluded())
          << "mesh " << mesh_index << " trial " << trial << " visible " << visible.visible_length();
      if (trial % 10 == 0) {
        EXPECT_TRUE(brute_force(mesh, x, a, b).fully_occluded());
      }
      ++configurations;
    }
  }
  EXPECT_EQ(configurations, 1200);
}

TEST(LineQuery, OccludedAgreesWithBruteForceRays) {
  TriangleMesh mesh = random_triangles_mesh(3000, {-1, -1, -1}, {1, 1, 1}, 0.05, 81);
  LineQuery line_query(mesh.positions, mesh.indices);
  Random random(82);
  int blocked = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    Vec3 x = random.in_box({-1.5, -1.5, -1.5}, {1.5, 1.5, 1.5});
    Vec3 p = random.in_box({-1.5, -1.5, -1.5}, {1.5, 1.5, 1.5});
    bool expected = ray_blocked_brute_force(mesh, x, p);
    EXPECT_EQ(line_query.occluded(x, p), expected) << trial;
    blocked += expected;
  }
  EXPECT_GT(blocked, 200);
  EXPECT_LT(blocked, 1800);
}

}  // namespace
}  // namespace penumbra
