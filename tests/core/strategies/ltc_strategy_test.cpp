// LtcStrategy (`ltc`): chi-square of its samples against its own area pdf; pdf(sample) equal to
// the sample's pdf; the pdf integrates to 1 over the light; the LTC's polygon integral (Peters
// Eq. 10) against quadrature; lambert and phong receivers give exactly psa; finite results for
// tiny distant lights, lights crossing the horizon, points behind the light.

#include "core/strategies/ltc_strategy.h"

#include <gtest/gtest.h>

#include <random>
#include <stdexcept>
#include <vector>

#include "core/materials/ltc_ggx_table.h"
#include "core/strategies/psa_strategy.h"
#include "tests/support/polygon_test_util.h"

namespace penumbra {
namespace {

using polygon_test::light_facing;
using polygon_test::shading_point;
using polygon_test::uniform;

Material ggx_material(double roughness) {
  Material m;
  m.type = MaterialType::Ggx;
  m.diffuse = {0.3, 0.2, 0.1};
  m.specular = {0.9, 0.5, 0.04};
  m.roughness = roughness;
  return m;
}

struct Configuration {
  std::string name;
  Light light;
  Vec3 position, normal, wo;
  double roughness;
};

// Lights above a point with normal +y, viewed so that the specular highlight falls on (or near)
// the light; roughness from glossy to rough.
std::vector<Configuration> configurations() {
  using polygon_test::quad_light;
  std::vector<Configuration> c;
  Light ceiling = quad_light({-0.5, 1, -0.5}, {1, 0, 0}, {0, 0, 1});
  c.push_back(
      {"ceiling quad, normal view, alpha 0.5", ceiling, {0.1, 0, 0.2}, {0, 1, 0}, {0, 1, 0}, 0.5});
  c.push_back({"ceiling quad, oblique view, alpha 0.25",
               ceiling,
               {0.3, 0, 0},
               {0, 1, 0},
               {1, 0.8, 0.3},
               0.25});
  c.push_back({"offset quad, grazing view, alpha 0.35",
               quad_light({0.5, 0.6, -0.5}, {1.5, 0, 0}, {0, 0, 1}),
               {0, 0, 0},
               {0, 1, 0},
               {-1, 0.25, 0},
               0.35});
  c.push_back({"tilted triangle, alpha 0.8",
               light_facing({{0.3, 1.2, -0.4}, {1.1, 0.9, 0.2}, {-0.2, 1.4, 0.5}}, {0, 0, 0}),
               {0, 0, 0},
               {0.3, 1, -0.2},
               {-0.5, 1, 0.2},
               0.8});
  c.push_back(
      {"pentagon crossing the horizon, alpha 0.3",
       light_facing({{1, 0.5, -1}, {1, 1.2, -0.6}, {1, 1.2, 0.6}, {1, 0.5, 1}, {1, -0.4, 0}},
                    {0, 0, 0}),
       {0, 0, 0},
       {-0.3, 1, 0},
       {-1, 0.6, 0.1},
       0.3});
  return c;
}

TEST(LtcStrategy, SamplesFollowTheirPdf) {
  for (const Configuration& c : configurations()) {
    Material material = ggx_material(c.roughness);
    ShadingPoint sp = shading_point(c.position, c.normal, c.wo, &material);
    LtcStrategy strategy(sp, c.light);
    const int count = 200000;
    auto result = polygon_test::chi_square_on_light(
        c.light.vertices,
        [&](const Vec2& u) -> std::optional<Vec3> {
          std::optional<LightPoint> p = strategy.sample(u);
          if (!p) return std::nullopt;
          return p->position;
        },
        [&](const Vec3& x) { return strategy.pdf(x); }, count, 24, 61, 16);
    EXPECT_LT(result.statistic, result.critical)
        << c.name << ": chi-square " << result.statistic << " with " << result.dof << " dof";
    EXPECT_LT(result.missing, count / 1000) << c.name;
  }
}

TEST(LtcStrategy, ChiSquareDetectsAWrongPdf) {
  // The same test with the density of a different roughness must fail.
  const Configuration c = configurations()[1];
  Material material = ggx_material(c.roughness), other = ggx_material(c.roughness * 1.3);
  ShadingPoint sp = shading_point(c.position, c.normal, c.wo, &material);
  ShadingPoint other_sp = shading_point(c.position, c.normal, c.wo, &other);
  LtcStrategy strategy(sp, c.light), wrong(other_sp, c.light);
  auto result = polygon_test::chi_square_on_light(
      c.light.vertices,
      [&](const Vec2& u) -> std::optional<Vec3> {
        std::optional<LightPoint> p = strategy.sample(u);
        if (!p) return std::nullopt;
        return p->position;
      },
      [&](const Vec3& x) { return wrong.pdf(x); }, 200000, 24, 67, 16);
  EXPECT_GT(result.statistic, result.critical);
}

TEST(LtcStrategy, PdfOfASampleIsTheSamplePdf) {
  std::mt19937_64 rng(71);
  int checked = 0;
  for (const Configuration& c : configurations()) {
    for (double roughness : {0.02, 0.1, c.roughness, 1.0}) {
      Material material = ggx_material(roughness);
      ShadingPoint sp = shading_point(c.position, c.normal, c.wo, &material);
      LtcStrategy strategy(sp, c.light);
      for (int k = 0; k < 500; ++k) {
        std::optional<LightPoint> p = strategy.sample({uniform(rng), uniform(rng)});
        if (!p) continue;
        ASSERT_TRUE(std::isfinite(p->pdf_area));
        EXPECT_NEAR(strategy.pdf(p->position), p->pdf_area, 1e-7 * p->pdf_area)
            << c.name << " roughness " << roughness;
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 5000);
}

// The area pdf integrates to one over the light, and the LTC's mass on the light (Eq. 10, the
// projected solid angle of the transformed polygon) matches quadrature of p_M over the light.
TEST(LtcStrategy, PdfIsNormalizedAndTheLtcIntegralMatchesQuadrature) {
  for (const Configuration& c : configurations()) {
    Material material = ggx_material(c.roughness);
    ShadingPoint sp = shading_point(c.position, c.normal, c.wo, &material);
    LtcStrategy strategy(sp, c.light);
    double total = polygon_test::integrate_over_polygon(
        c.light.vertices, [&](const Vec3& x) { return strategy.pdf(x); }, 600);
    EXPECT_NEAR(total, 1.0, 2e-3) << c.name;
    Frame frame = ltc_shading_frame(sp.normal, sp.wo);
    double ltc_mass = polygon_test::integrate_over_polygon(
        c.light.vertices,
        [&](const Vec3& x) {
          Vec3 d = x - sp.position;
          double r2 = length_squared(d);
          Vec3 w = d / std::sqrt(r2);
          return strategy.ltc().density(frame.to_local(w)) * std::abs(dot(c.light.normal, w)) / r2;
        },
        600);
    EXPECT_NEAR(strategy.ltc_integral(), ltc_mass, 2e-3 * ltc_mass) << c.name;
    EXPECT_GT(strategy.ltc_integral(), 0) << c.name;
    EXPECT_LE(strategy.ltc_integral(), 1.0 + 1e-12) << c.name;
  }
}

// Lambert (and phong, which is not fitted) use the identity: ltc is psa, sample for sample.
TEST(LtcStrategy, LambertAndPhongReceiversEqualProjectedSolidAngle) {
  Material lambert, phong;
  phong.type = MaterialType::Phong;
  phong.kd = {0.2, 0.2, 0.2};
  phong.ks = {0.5, 0.5, 0.5};
  phong.exponent = 40;
  std::mt19937_64 rng(73);
  for (const Configuration& c : configurations())
    for (const Material* material : {&lambert, &phong}) {
      ShadingPoint sp = shading_point(c.position, c.normal, c.wo, material);
      LtcStrategy ltc(sp, c.light);
      ProjectedSolidAngleStrategy psa(sp, c.light);
      EXPECT_EQ(ltc.lobe_albedo(), (Rgb{0, 0, 0}));
      EXPECT_NEAR(ltc.ltc_integral(), psa.projected_solid_angle() / kPi, 1e-14);
      for (int k = 0; k < 200; ++k) {
        Vec2 u{uniform(rng), uniform(rng)};
        std::optional<LightPoint> a = ltc.sample(u), b = psa.sample(u);
        ASSERT_EQ(a.has_value(), b.has_value()) << c.name;
        if (!a) continue;
        // The frames differ (ltc's follows wo), so the sample maps differ: compare densities.
        EXPECT_NEAR(ltc.pdf(b->position), b->pdf_area, 1e-9 * b->pdf_area) << c.name;
        EXPECT_NEAR(psa.pdf(a->position), a->pdf_area, 1e-9 * a->pdf_area) << c.name;
      }
    }
}

// With a wo along the normal both use Frame::from_normal: then even the samples coincide.
TEST(LtcStrategy, LambertSamplesCoincideWithPsaForNormalView) {
  Material lambert;
  Light light = polygon_test::quad_light({-0.5, 1, -0.5}, {1, 0, 0}, {0, 0, 1});
  ShadingPoint sp = shading_point({0.1, 0, 0.2}, {0, 1, 0}, {0, 1, 0}, &lambert);
  LtcStrategy ltc(sp, light);
  ProjectedSolidAngleStrategy psa(sp, light);
  std::mt19937_64 rng(79);
  for (int k = 0; k < 1000; ++k) {
    Vec2 u{uniform(rng), uniform(rng)};
    std::optional<LightPoint> a = ltc.sample(u), b = psa.sample(u);
    ASSERT_TRUE(a && b);
    EXPECT_NEAR(length(a->position - b->position), 0.0, 1e-12);
    EXPECT_NEAR(a->pdf_area, b->pdf_area, 1e-12 * b->pdf_area);
  }
}

TEST(LtcStrategy, PointsBehindTheLightGetNoSamples) {
  Material material = ggx_material(0.3);
  Light light = polygon_test::quad_light({-0.5, 1, -0.5}, {1, 0, 0}, {0, 0, 1});  // emits -y
  for (const Vec3& position : {Vec3{0, 2, 0}, Vec3{3, 1, 0}}) {
    ShadingPoint sp = shading_point(position, {0, -1, 0}, {0.3, -1, 0}, &material);
    LtcStrategy ltc(sp, light);
    EXPECT_FALSE(ltc.sample({0.4, 0.6}).has_value());
    EXPECT_EQ(ltc.pdf({0, 1, 0}), 0.0);
    EXPECT_EQ(ltc.ltc_integral(), 0.0);
  }
  Light disk;
  disk.type = LightType::Disk;
  disk.center = {0, 1, 0};
  disk.normal = {0, -1, 0};
  disk.radius = 0.3;
  ShadingPoint sp = shading_point({0, 0, 0}, {0, 1, 0}, {0, 1, 0}, &material);
  EXPECT_THROW(LtcStrategy(sp, disk), std::invalid_argument);
}

// Fig. 7 and Fig. 12 stress cases, every roughness, views down to grazing: finite samples and
// densities, samples on the light.
TEST(LtcStrategy, StressConfigurationsStayFinite) {
  std::mt19937_64 rng(83);
  for (double side : {1e-2, 1e-3, 1.0}) {
    for (int trial = 0; trial < 200; ++trial) {
      Vec3 normal = normalize(Vec3{uniform(rng) - 0.5, 1.0, uniform(rng) - 0.5});
      Vec3 wo = normalize(Vec3{uniform(rng) - 0.5, 1e-3 + uniform(rng), uniform(rng) - 0.5});
      if (dot(wo, normal) <= 0) wo = normal;
      double distance = side < 0.5 ? 30.0 : 1.0;
      Vec3 center{distance * (uniform(rng) - 0.5), distance, distance * (uniform(rng) - 0.5)};
      Light light = polygon_test::quad_light(center, {side, 0, 0}, {0, 0, side});
      if (trial % 4 == 0)  // Fig. 12: edges parallel to the normal, crossing the horizon
        light = polygon_test::quad_light({1, -0.5, -0.5}, {0, 0, 1}, {0, 1.5, 0}),
        normal = {0, 1, 0};
      Material material = ggx_material(trial % 3 == 0 ? 1e-4 : uniform(rng));
      ShadingPoint sp = shading_point({0, 0, 0}, normal, wo, &material);
      LtcStrategy ltc(sp, light);
      ASSERT_TRUE(std::isfinite(ltc.ltc_integral()));
      for (int k = 0; k < 20; ++k) {
        std::optional<LightPoint> p = ltc.sample({uniform(rng), uniform(rng)});
        if (!p) continue;
        ASSERT_TRUE(is_finite(p->position));
        ASSERT_TRUE(std::isfinite(p->pdf_area));
        ASSERT_GT(p->pdf_area, 0);
        double pdf = ltc.pdf(p->position);
        ASSERT_TRUE(std::isfinite(pdf));
      }
    }
  }
}

}  // namespace
}  // namespace penumbra
