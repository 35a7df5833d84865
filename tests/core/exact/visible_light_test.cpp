// The exact visible part of a polygonal light: against Lambert's closed form without occluders
// (also near the light's plane and with the light cut by the horizon), against the difference of
// two closed forms with one occluder whose shadow lies inside the light, meshes that share edges
// (a quad cut into 2 and into 128 triangles must give the single quad's value: no leak along
// the shared edges), and against brute-force stratified area sampling with exact visibility on
// random occluder scenes.

#include "core/exact/visible_light.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "core/lines/line_query.h"
#include "core/lines/shadow_triangle.h"
#include "core/math/lambert_polygon.h"

namespace penumbra {
namespace {

// A 1 x 1 square light at height 2 facing down.
const std::vector<Vec3> kLight = {{-0.5, 2, -0.5}, {0.5, 2, -0.5}, {0.5, 2, 0.5}, {-0.5, 2, 0.5}};
const Vec3 kLightNormal{0, -1, 0};

struct Mesh {
  std::vector<Vec3> positions;
  std::vector<uint32_t> indices;
  void add_triangle(const Vec3& a, const Vec3& b, const Vec3& c) {
    const uint32_t base = uint32_t(positions.size());
    positions.insert(positions.end(), {a, b, c});
    indices.insert(indices.end(), {base, base + 1, base + 2});
  }
  // A horizontal square [x0, x1] x [z0, z1] at height y cut into n x n cells of 2 triangles,
  // with shared vertices.
  void add_grid(double x0, double x1, double z0, double z1, double y, int n) {
    const uint32_t base = uint32_t(positions.size());
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i)
        positions.push_back({x0 + (x1 - x0) * i / n, y, z0 + (z1 - z0) * j / n});
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const uint32_t a = base + uint32_t(j * (n + 1) + i), b = a + 1, c = a + uint32_t(n + 1),
                       d = c + 1;
        indices.insert(indices.end(), {a, b, d, a, d, c});
      }
  }
};

double exact_value(const Mesh& mesh, const Vec3& x, const Vec3& n) {
  // A far-away dummy triangle keeps the BVH non-empty when the mesh is.
  Mesh with_dummy = mesh;
  with_dummy.add_triangle({100, -50, 100}, {101, -50, 100}, {100, -50, 101});
  LineQuery query(with_dummy.positions, with_dummy.indices);
  VisibleLightScratch scratch;
  return visible_projected_solid_angle(x, n, kLight, kLightNormal, query, scratch);
}

double lambert(const Vec3& x, const Vec3& n, const std::vector<Vec3>& polygon) {
  return kPi * lambert_polygon_form_factor(x, n, polygon);
}

TEST(VisibleLight, WithoutOccludersItIsLambertsFormula) {
  const Mesh empty;
  for (const Vec3& x :
       {Vec3{0, 0, 0}, Vec3{0.3, 1.2, -0.2}, Vec3{2, 0.5, 1}, Vec3{0.1, 2 - 1e-6, 0}}) {
    const Vec3 n{0, 1, 0};
    const double expected = lambert(x, n, kLight);
    EXPECT_NEAR(exact_value(empty, x, n), expected, 1e-13 * expected) << x.x << " " << x.y;
  }
  // Tilted receivers: the light partly below the horizon.
  for (const Vec3& n : {normalize(Vec3{1, 0.2, 0}), normalize(Vec3{0, 0.05, -1}), Vec3{1, 0, 0}}) {
    const Vec3 x{0, 1.5, 0};
    const double expected = lambert(x, n, kLight);
    ASSERT_GT(expected, 0);
    EXPECT_NEAR(exact_value(empty, x, n), expected, 1e-12 * expected);
  }
  // Behind the light, or wholly below the horizon: nothing.
  EXPECT_EQ(exact_value(empty, {0, 3, 0}, {0, 1, 0}), 0.0);
  EXPECT_EQ(exact_value(empty, {0, 1, 0}, {0, -1, 0}), 0.0);
}

TEST(VisibleLight, AnOccluderInsideThePyramidSubtractsItsShadow) {
  // A 0.25 x 0.25 square at height 1, right under the light's centre: from x = (0, 0, 0) its
  // shadow on the light's plane is a 0.5 x 0.5 square, wholly inside the light. (Occluder
  // vertices are stored as floats, as Embree sees them: these are exact in float.)
  Mesh mesh;
  mesh.add_grid(-0.125, 0.125, -0.125, 0.125, 1.0, 1);
  const Vec3 x{0, 0, 0}, n{0, 1, 0};
  const std::vector<Vec3> shadow = {
      {-0.25, 2, -0.25}, {0.25, 2, -0.25}, {0.25, 2, 0.25}, {-0.25, 2, 0.25}};
  const double expected = lambert(x, n, kLight) - lambert(x, n, shadow);
  EXPECT_NEAR(exact_value(mesh, x, n), expected, 1e-9 * expected);
  // Off centre: the shadow is the square projected from x (scale 2 / 1 about x).
  const Vec3 x2{0.05, 0, -0.03};
  std::vector<Vec3> shadow2;
  for (const Vec3& corner : std::vector<Vec3>{
           {-0.125, 1, -0.125}, {0.125, 1, -0.125}, {0.125, 1, 0.125}, {-0.125, 1, 0.125}})
    shadow2.push_back(x2 + 2.0 * (corner - x2));
  const double expected2 = lambert(x2, n, kLight) - lambert(x2, n, shadow2);
  EXPECT_NEAR(exact_value(mesh, x2, n), expected2, 1e-9 * expected2);
}

TEST(VisibleLight, SharedEdgeMeshesDoNotLeak) {
  const Vec3 n{0, 1, 0};
  for (const Vec3& x : {Vec3{0, 0, 0}, Vec3{0.37, 0.2, -0.21}, Vec3{-0.6, 0.5, 0.4}}) {
    Mesh one, two, many;
    one.add_grid(-0.3, 0.25, -0.2, 0.35, 1.1, 1);   // 2 triangles
    two.add_grid(-0.3, 0.25, -0.2, 0.35, 1.1, 2);   // 8 triangles
    many.add_grid(-0.3, 0.25, -0.2, 0.35, 1.1, 8);  // 128 triangles
    const double a = exact_value(one, x, n), b = exact_value(two, x, n),
                 c = exact_value(many, x, n);
    EXPECT_NEAR(b, a, 1e-9 * a) << x.x;
    EXPECT_NEAR(c, a, 1e-9 * a) << x.x;
  }
}

// Brute force: stratified uniform samples over the light (m x m strata), each visible when no
// occluder blocks the segment (the exact segment test of core/lines/shadow_triangle.h), giving
// integral cos_x cos_l / r^2 dA.
double brute_force(const Mesh& mesh, const Vec3& x, const Vec3& n, int m, uint32_t seed) {
  LineQuery query(mesh.positions, mesh.indices);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform(0, 1);
  double sum = 0;
  for (int j = 0; j < m; ++j)
    for (int i = 0; i < m; ++i) {
      const double s = (i + uniform(rng)) / m, t = (j + uniform(rng)) / m;
      const Vec3 p{-0.5 + s, 2, -0.5 + t};
      const Vec3 d = p - x;
      const double r2 = length_squared(d);
      const double cos_x = dot(n, d) / std::sqrt(r2), cos_l = dot(kLightNormal, -d) / std::sqrt(r2);
      if (cos_x <= 0 || cos_l <= 0) continue;
      if (query.occluded(x, p)) continue;
      sum += cos_x * cos_l / r2;
    }
  return sum / (double(m) * m);  // the light's area is 1
}

TEST(VisibleLight, MatchesBruteForceAreaSamplingOnRandomOccluders) {
  std::mt19937_64 rng(2024);
  std::uniform_real_distribution<double> uniform(-1, 1);
  for (int scene = 0; scene < 4; ++scene) {
    Mesh mesh;
    for (int k = 0; k < 12; ++k) {
      const Vec3 center{0.5 * uniform(rng), 1.0 + 0.4 * uniform(rng), 0.5 * uniform(rng)};
      const double size = 0.15;
      mesh.add_triangle(center + size * Vec3{uniform(rng), 0.3 * uniform(rng), uniform(rng)},
                        center + size * Vec3{uniform(rng), 0.3 * uniform(rng), uniform(rng)},
                        center + size * Vec3{uniform(rng), 0.3 * uniform(rng), uniform(rng)});
    }
    const Vec3 x{0.3 * uniform(rng), 0, 0.3 * uniform(rng)};
    const Vec3 n = normalize(Vec3{0.2 * uniform(rng), 1, 0.2 * uniform(rng)});
    const double exact = exact_value(mesh, x, n);
    // 1000 x 1000 strata: the error of stratified sampling of a function with discontinuities
    // along curves is about (perimeter / strata) ^ 1.5; measured spread between seeds below.
    const double a = brute_force(mesh, x, n, 1000, 1), b = brute_force(mesh, x, n, 1000, 2);
    const double spread = std::abs(a - b) + 1e-6 * exact;
    std::printf("scene %d: exact %.9f, brute force %.9f / %.9f\n", scene, exact, a, b);
    EXPECT_NEAR(exact, 0.5 * (a + b), 4 * spread) << scene;
    EXPECT_LT(exact, lambert(x, n, kLight));
  }
}

}  // namespace
}  // namespace penumbra
