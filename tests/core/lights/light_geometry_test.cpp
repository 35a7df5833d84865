// Light geometry: one-sided emission and profiles, uniform points (chi-square against the
// uniform area density), ray intersection and containment.

#include "core/lights/light_geometry.h"

#include <gtest/gtest.h>

#include <functional>
#include <limits>
#include <vector>

#include "tests/core/strategies/test_support.h"

namespace penumbra {
namespace {

using test::Rng;

Light tilted_parallelogram() {
  return test::quad_light({0.3, 2.0, -0.2}, {1.0, 0.1, 0.2}, {0.4, -0.2, 0.9});
}
Light pentagon() {
  return test::regular_polygon_light({0.5, 1.0, 0.2}, {0.2, -1, 0.1}, 0.7, 5);
}
Light disk() {
  return test::disk_light({0, 1.5, 0.3}, {0.1, -1, 0.3}, 0.4);
}

TEST(EmittedRadiance, IsOneSided) {
  for (const Light& light : {tilted_parallelogram(), pentagon(), disk()}) {
    Vec3 p = light.centroid;
    EXPECT_EQ(emitted_radiance(light, p, light.normal), light.radiance);
    Frame f = Frame::from_normal(light.normal);
    EXPECT_EQ(emitted_radiance(light, p, normalize(f.s + 0.01 * light.normal)), light.radiance);
    EXPECT_TRUE(is_black(emitted_radiance(light, p, -light.normal)));
    EXPECT_TRUE(is_black(emitted_radiance(light, p, normalize(f.s - 1e-12 * light.normal))));
  }
}

TEST(EmittedRadiance, GaussianProfileOfQuadsAndDisks) {
  Light quad = test::quad_light({0, 0, 0}, {2, 0, 0}, {0, 1, 0}, {3, 3, 3});
  quad.profile = ProfileType::Gaussian;
  quad.sigma = 0.25;
  Vec3 up{0, 0, 1};
  EXPECT_NEAR(emitted_radiance(quad, {1, 0.5, 0}, up).x, 3.0, 1e-14);  // centre: r = 0
  double edge = 3.0 * std::exp(-1.0 / (2 * 0.25 * 0.25));              // edge midpoint: r = 1
  EXPECT_NEAR(emitted_radiance(quad, {2, 0.5, 0}, up).x, edge, 1e-14 * 3);
  EXPECT_NEAR(emitted_radiance(quad, {1, 1, 0}, up).x, edge, 1e-14 * 3);
  double corner = 3.0 * std::exp(-2.0 / (2 * 0.25 * 0.25));  // corner: r^2 = 2
  EXPECT_NEAR(emitted_radiance(quad, {0, 0, 0}, up).x, corner, 1e-14 * 3);
  // Quarter of the way along edge1 (s = 0.25, t = 0.5): r = 0.5.
  EXPECT_NEAR(emitted_radiance(quad, {0.5, 0.5, 0}, up).x,
              3.0 * std::exp(-0.25 / (2 * 0.25 * 0.25)), 1e-14 * 3);

  Light d = test::disk_light({0, 0, 0}, {0, 0, 1}, 2.0, {1, 2, 3});
  d.profile = ProfileType::Gaussian;
  d.sigma = 0.5;
  EXPECT_NEAR(emitted_radiance(d, {0, 0, 0}, up).z, 3.0, 1e-14);
  EXPECT_NEAR(emitted_radiance(d, {1, 0, 0}, up).z, 3.0 * std::exp(-0.25 / 0.5), 1e-14);
  EXPECT_NEAR(emitted_radiance(d, {0, 2, 0}, up).y, 2.0 * std::exp(-1.0 / 0.5), 1e-14);

  // Polygons: constant only.
  Light poly = pentagon();
  poly.profile = ProfileType::Gaussian;
  EXPECT_EQ(emitted_radiance(poly, poly.vertices[0], poly.normal), poly.radiance);
}

// Chi-square of light_point_uniform against the uniform density, on a chart of the light.
struct Chart {
  int bins = 16;
  std::function<int(const Vec3&)> bin;
  std::vector<double> expected_fraction;
};

Chart quad_chart(const Light& light) {
  Chart c;
  c.bin = [light, bins = c.bins](const Vec3& p) {
    // (s, t) by the dual basis.
    Vec3 n = cross(light.edge1, light.edge2);
    Vec3 d = p - light.origin;
    double s = dot(cross(d, light.edge2), n) / dot(n, n);
    double t = dot(cross(light.edge1, d), n) / dot(n, n);
    int i = std::clamp(static_cast<int>(s * bins), 0, bins - 1);
    int j = std::clamp(static_cast<int>(t * bins), 0, bins - 1);
    return i * bins + j;
  };
  c.expected_fraction.assign(c.bins * c.bins, 1.0 / (c.bins * c.bins));
  return c;
}

Chart disk_chart(const Light& light) {
  Chart c;
  Frame f = Frame::from_normal(light.normal);
  c.bin = [light, f, bins = c.bins](const Vec3& p) {
    Vec3 d = p - light.center;
    double a = length_squared(d) / (light.radius * light.radius);
    double phi = std::atan2(dot(d, f.t), dot(d, f.s));
    if (phi < 0) phi += 2 * kPi;
    int i = std::clamp(static_cast<int>(a * bins), 0, bins - 1);
    int j = std::clamp(static_cast<int>(phi / (2 * kPi) * bins), 0, bins - 1);
    return i * bins + j;
  };
  c.expected_fraction.assign(c.bins * c.bins, 1.0 / (c.bins * c.bins));
  return c;
}

Chart polygon_chart(const Light& light) {
  // Bins over the polygon's bounding rectangle in its plane; the covered fraction of each bin by
  // a fine sub-grid (64 x 64 per bin).
  Chart c;
  Frame f = Frame::from_normal(light.normal);
  double lo_s = 1e300, hi_s = -1e300, lo_t = 1e300, hi_t = -1e300;
  for (const Vec3& v : light.vertices) {
    lo_s = std::min(lo_s, dot(v - light.centroid, f.s));
    hi_s = std::max(hi_s, dot(v - light.centroid, f.s));
    lo_t = std::min(lo_t, dot(v - light.centroid, f.t));
    hi_t = std::max(hi_t, dot(v - light.centroid, f.t));
  }
  c.bin = [=, bins = c.bins](const Vec3& p) {
    double s = (dot(p - light.centroid, f.s) - lo_s) / (hi_s - lo_s);
    double t = (dot(p - light.centroid, f.t) - lo_t) / (hi_t - lo_t);
    int i = std::clamp(static_cast<int>(s * bins), 0, bins - 1);
    int j = std::clamp(static_cast<int>(t * bins), 0, bins - 1);
    return i * bins + j;
  };
  int sub = 64, n = c.bins * sub;
  c.expected_fraction.assign(c.bins * c.bins, 0.0);
  double cell = (hi_s - lo_s) * (hi_t - lo_t) / (double(n) * n);
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b) {
      Vec3 p = light.centroid + (lo_s + (a + 0.5) / n * (hi_s - lo_s)) * f.s +
               (lo_t + (b + 0.5) / n * (hi_t - lo_t)) * f.t;
      if (light_contains(light, p)) c.expected_fraction[(a / sub) * c.bins + b / sub] += cell;
    }
  for (double& e : c.expected_fraction) e /= light.area;
  return c;
}

void check_uniform(const Light& light, const Chart& chart, uint64_t seed) {
  const int samples = 300000;
  std::vector<double> observed(chart.expected_fraction.size(), 0.0), expected;
  Rng rng(seed);
  for (int i = 0; i < samples; ++i) {
    Vec3 p = light_point_uniform(light, rng.uniform2());
    ASSERT_TRUE(light_contains(light, p)) << i;
    observed[chart.bin(p)] += 1;
  }
  for (double f : chart.expected_fraction) expected.push_back(f * samples);
  auto result = test::chi_square_test(observed, expected);
  EXPECT_TRUE(result.passed) << result.summary();
}

TEST(LightPointUniform, ParallelogramIsUniform) {
  Light light = tilted_parallelogram();
  check_uniform(light, quad_chart(light), 1);
}
TEST(LightPointUniform, PentagonIsUniform) {
  Light light = pentagon();
  check_uniform(light, polygon_chart(light), 2);
}
TEST(LightPointUniform, TriangleIsUniform) {
  Light light = test::polygon_light({{0, 0, 0}, {1, 0, 0.2}, {0.1, 0.9, 0}});
  check_uniform(light, polygon_chart(light), 3);
}
TEST(LightPointUniform, DiskIsUniform) {
  Light light = disk();
  check_uniform(light, disk_chart(light), 4);
}

TEST(IntersectLight, HitsTheAimedPointFromEitherSideAndMissesOutside) {
  Rng rng(8);
  for (const Light& light : {tilted_parallelogram(), pentagon(), disk()}) {
    for (int i = 0; i < 2000; ++i) {
      Vec3 target = light_point_uniform(light, rng.uniform2());
      double side = i % 2 ? 1.0 : -1.0;
      Vec3 origin = target + side * 3.0 * normalize(light.normal + 0.5 * rng.unit_vector());
      Vec3 direction = normalize(target - origin);
      auto hit =
          intersect_light(light, origin, direction, 0, std::numeric_limits<double>::infinity());
      ASSERT_TRUE(hit.has_value());
      EXPECT_LE(length(hit->point - target), 1e-12 * 3);
      EXPECT_NEAR(hit->distance, length(target - origin), 1e-12 * 3);
      // Window of the ray: t_max before the light, t_min after it.
      EXPECT_FALSE(intersect_light(light, origin, direction, 0, 0.5 * hit->distance));
      EXPECT_FALSE(intersect_light(light, origin, direction, 1.5 * hit->distance, 1e30));
      // Away from the light: no hit.
      EXPECT_FALSE(intersect_light(light, origin, -direction, 0, 1e30));
    }
    // Outside the light's outline (beyond its extent, in its plane): miss.
    Frame f = Frame::from_normal(light.normal);
    Vec3 outside = light.centroid + 5.0 * f.s;
    Vec3 origin = outside + light.normal;
    EXPECT_FALSE(intersect_light(light, origin, -light.normal, 0, 1e30));
    // Parallel to the plane: miss.
    EXPECT_FALSE(intersect_light(light, light.centroid + light.normal, f.t, 0, 1e30));
  }
}

TEST(LightContains, ScaleRelativeTolerance) {
  for (double scale : {1e-3, 1.0, 1e3}) {
    for (Vec3 offset : {Vec3{0, 0, 0}, Vec3{40, -40, 40}}) {
      Light quad = test::quad_light(offset + scale * Vec3{0, 0, 0}, scale * Vec3{1, 0, 0},
                                    scale * Vec3{0, 1, 0});
      Light poly = test::polygon_light(
          {offset, offset + scale * Vec3{1, 0, 0}, offset + scale * Vec3{0, 1, 0}});
      Light d = test::disk_light(offset, {0, 0, 1}, scale);
      for (const Light* light : {&quad, &poly, &d}) {
        Vec3 inside = light->type == LightType::Disk ? offset + scale * Vec3{0.3, 0.3, 0}
                                                     : offset + scale * Vec3{0.2, 0.2, 0};
        EXPECT_TRUE(light_contains(*light, inside));
        EXPECT_FALSE(light_contains(*light, inside + Vec3{0, 0, 1e-4 * scale}));
        if (light->type != LightType::Disk) {
          EXPECT_FALSE(light_contains(*light, offset + scale * Vec3{-0.01, 0.5, 0}));
        } else {
          EXPECT_FALSE(light_contains(*light, offset + scale * Vec3{0.6, -0.8001, 0}));
          EXPECT_TRUE(light_contains(*light, offset + scale * Vec3{0.6, -0.7999, 0}));
        }
        EXPECT_FALSE(light_contains(*light, offset + scale * Vec3{1.01, 0.0, 0}));
      }
    }
  }
}

TEST(LightFacesPoint, FrontBackAndPlane) {
  Light light = pentagon();
  EXPECT_TRUE(light_faces_point(light, light.centroid + 1e-4 * light.normal));
  EXPECT_FALSE(light_faces_point(light, light.centroid - 1e-4 * light.normal));
  Frame f = Frame::from_normal(light.normal);
  EXPECT_FALSE(light_faces_point(light, light.centroid + 3.0 * f.s));
  EXPECT_NEAR(light_plane_height(light, light.centroid + 2.5 * light.normal + f.t), 2.5, 1e-12);
}

}  // namespace
}  // namespace penumbra
