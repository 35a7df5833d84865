// No NaN or Inf from any strategy in degenerate configurations (METHODS.md): the shading point
// on the light's plane, behind the light, 1e-4 and 1e-12 in front of it, a 1 cm light 40 m away,
// grazing and averted normals, glossy extremes (phong n = 10^4, ggx alpha = 1e-4) and the
// corners of the random-number square. Where the light sends nothing, the estimate is 0.

#include <gtest/gtest.h>

#include <vector>

#include "core/lights/light_geometry.h"
#include "core/materials/bsdf.h"
#include "core/strategies/area_strategy.h"
#include "core/strategies/bsdf_strategy.h"
#include "core/strategies/solid_angle_strategy.h"
#include "tests/core/strategies/test_support.h"

namespace penumbra {
namespace {

std::vector<Light> lights_at(double scale, const Vec3& offset) {
  std::vector<Light> lights;
  // All face down (-y).
  lights.push_back(test::quad_light(offset, scale * Vec3{1, 0, 0}, scale * Vec3{0, 0, 1}));
  lights.push_back(test::quad_light(offset, scale * Vec3{1, 0, 0}, scale * Vec3{0.4, 0, 1}));
  lights.push_back(test::polygon_light(
      {offset, offset + scale * Vec3{1, 0, 0}, offset + scale * Vec3{0.2, 0, 0.9}}));
  lights.push_back(test::regular_polygon_light(offset, {0, -1, 0}, 0.5 * scale, 5));
  lights.push_back(test::disk_light(offset, {0, -1, 0}, 0.5 * scale));
  for (const Light& light : lights) EXPECT_LT(light.normal.y, 0);
  return lights;
}

std::vector<Material> materials() {
  return {test::lambert(), test::phong({0.1, 0.1, 0.1}, {0.8, 0.8, 0.8}, 1e4),
          test::ggx({0.05, 0.05, 0.05}, {0.9, 0.9, 0.9}, 1e-4),
          test::ggx({0.05, 0.05, 0.05}, {0.9, 0.9, 0.9}, 1.0)};
}

std::vector<Vec2> random_numbers() {
  std::vector<Vec2> us = {{0, 0},
                          {0, 1},
                          {1, 0},
                          {1, 1},
                          {0x1.fffffffffffffp-1, 0x1.fffffffffffffp-1},
                          {0.5, 0x1.fffffffffffffp-1},
                          {1e-300, 0.5}};
  test::Rng rng(77);
  for (int i = 0; i < 60; ++i) us.push_back(rng.uniform2());
  return us;
}

// Runs a strategy at a shading point; returns the largest estimate seen, failing on non-finite.
template <class Strategy>
double largest_estimate(const ShadingPoint& sp, const Light& light, const std::string& where) {
  Strategy strategy(sp, light);
  double largest = 0;
  for (const Vec2& u : random_numbers()) {
    auto s = strategy.sample(u);
    if (!s) continue;
    EXPECT_TRUE(is_finite(s->position)) << where;
    EXPECT_TRUE(std::isfinite(s->pdf_area) && s->pdf_area > 0) << where;
    double pdf = strategy.pdf(s->position);
    EXPECT_TRUE(std::isfinite(pdf) && pdf >= 0) << where;
    Vec3 d = s->position - sp.position;
    double r2 = length_squared(d);
    if (!(r2 > 0)) continue;
    Vec3 wi = d / std::sqrt(r2);
    Rgb f = eval_bsdf(*sp.material, sp.normal, sp.wo, wi);
    Rgb le = emitted_radiance(light, s->position, -wi);
    double cos_x = std::max(0.0, dot(sp.normal, wi));
    double value = luminance(f * le) * cos_x * std::abs(dot(light.normal, wi)) / (r2 * s->pdf_area);
    EXPECT_TRUE(std::isfinite(value)) << where;
    largest = std::max(largest, value);
  }
  // pdf() at arbitrary points of the light.
  test::Rng rng(3);
  for (int i = 0; i < 20; ++i) {
    double pdf = strategy.pdf(light_point_uniform(light, rng.uniform2()));
    EXPECT_TRUE(std::isfinite(pdf) && pdf >= 0) << where;
  }
  return largest;
}

void run_all(const ShadingPoint& sp, const Light& light, const std::string& where,
             bool light_sends_nothing) {
  double a = largest_estimate<AreaStrategy>(sp, light, where + " area");
  double s = largest_estimate<SolidAngleStrategy>(sp, light, where + " sa");
  double b = largest_estimate<BsdfStrategy>(sp, light, where + " bsdf");
  if (!light_faces_point(light, sp.position)) {
    // On the light's plane or behind it: no strategy can draw there, so every density is 0.
    test::Rng rng(4);
    for (int i = 0; i < 10; ++i) {
      Vec3 p = light_point_uniform(light, rng.uniform2());
      EXPECT_EQ(AreaStrategy(sp, light).pdf(p), 0.0) << where;
      EXPECT_EQ(SolidAngleStrategy(sp, light).pdf(p), 0.0) << where;
      EXPECT_EQ(BsdfStrategy(sp, light).pdf(p), 0.0) << where;
    }
  }
  if (light_sends_nothing) {
    EXPECT_EQ(a, 0.0) << where;
    EXPECT_EQ(s, 0.0) << where;
    EXPECT_EQ(b, 0.0) << where;
  }
}

TEST(StrategyRobustness, DegenerateShadingPoints) {
  // Lights in the plane y = 1 facing down (normal -y), except where stated.
  for (double scale : {1.0, 1e-3}) {
    Vec3 offset{0, 1, 0};
    for (Light light : lights_at(scale, offset)) {
      Vec3 c = light.centroid;
      Frame f = Frame::from_normal(light.normal);
      for (const Material& m : materials()) {
        auto sp = [&](Vec3 p, Vec3 n) {
          n = normalize(n);
          Vec3 wo = normalize(n + 0.3 * f.s);
          return ShadingPoint{p, n, wo, &m};
        };
        Vec3 down = light.normal;  // from the light towards the receivers below
        std::string name = m.name + " scale " + std::to_string(scale) + " light " +
                           std::to_string(static_cast<int>(light.type));
        // In the light's plane, inside and outside its outline.
        run_all(sp(c, {0, 1, 0}), light, name + " on plane inside", true);
        run_all(sp(c + 3.0 * scale * f.s, {0, 1, 0}), light, name + " on plane outside", true);
        // Behind the light.
        run_all(sp(c - 0.5 * scale * down, {0, 1, 0}), light, name + " behind", true);
        run_all(sp(c - 1e-4 * scale * down, {0, -1, 0}), light, name + " just behind", true);
        EXPECT_FALSE(light_faces_point(light, c - 1e-4 * scale * down));
        EXPECT_FALSE(light_faces_point(light, c));
        // Just in front of it, under its centre and under a vertex/edge.
        for (double h : {1e-4, 1e-12}) {
          run_all(sp(c + h * scale * down, -down), light, name + " close", false);
          Vec3 corner = light.type == LightType::Disk ? c + 0.5 * scale * f.s : light.vertices[1];
          run_all(sp(corner + h * scale * down, -down), light, name + " close to corner", false);
        }
        // Grazing normal: the light is exactly on the receiver's horizon plane.
        run_all(sp(c + 0.5 * scale * down, f.s), light, name + " grazing", false);
        run_all(sp(c + 0.5 * scale * down, f.s - 1e-9 * down), light, name + " grazing-", false);
        // The receiver faces away from the light.
        run_all(sp(c + 0.5 * scale * down, down), light, name + " averted", true);
      }
    }
  }
}

TEST(StrategyRobustness, TinyLightFarAway) {
  // 1 cm lights 40 m away, seen head on and at a glancing angle.
  for (Light light : lights_at(0.01, {0, 40, 0})) {
    for (const Material& m : materials()) {
      for (Vec3 p : {Vec3{0, 0, 0}, Vec3{39.9, 39.99, 0.0}, Vec3{-25, 0.5, 13}}) {
        ShadingPoint sp{p, {0, 1, 0}, normalize(Vec3{0.2, 1, 0}), &m};
        run_all(sp, light, m.name + " tiny far", false);
      }
    }
  }
  // The estimate is also right: sa on a tiny far rectangle (Lambert: albedo Le F, F ~ A / (pi
  // d^2) head on).
  Light tiny = test::quad_light({-0.005, 40, -0.005}, {0.01, 0, 0}, {0, 0, 0.01}, {1, 1, 1});
  ASSERT_LT(tiny.normal.y, 0);
  Material m = test::lambert({1, 1, 1});
  ShadingPoint sp{{0, 0, 0}, {0, 1, 0}, {0, 1, 0}, &m};
  SolidAngleStrategy sa(sp, tiny);
  auto s = sa.sample({0.3, 0.7});
  ASSERT_TRUE(s.has_value());
  Vec3 d = s->position;
  double r2 = length_squared(d);
  double value = (1 / kPi) * (d.y * d.y / r2) / (r2 * s->pdf_area);
  EXPECT_NEAR(value, 1e-4 / (kPi * 1600), 1e-6 * 1e-4 / (kPi * 1600));
}

}  // namespace
}  // namespace penumbra
