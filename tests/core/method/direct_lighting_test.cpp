// The direct-lighting estimator: unbiasedness of every point strategy and combination against
// Lambert's closed form, MIS weights that sum to one, determinism, finite values in degenerate
// configurations.
#include "core/method/direct_lighting.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/math/lambert_polygon.h"

namespace penumbra {
namespace {

class NeverOccluded : public Visibility {
 public:
  bool occluded(const Vec3&, const Vec3&, const Vec3&) const override { return false; }
};

Light polygon_light(std::vector<Vec3> vertices, Rgb radiance) {
  Light light;
  light.type = LightType::Polygon;
  light.vertices = std::move(vertices);
  light.radiance = radiance;
  light.normal = normalize(
      cross(light.vertices[1] - light.vertices[0], light.vertices[2] - light.vertices[0]));
  // Area and centroid of a planar polygon (fan from vertex 0).
  double area = 0;
  Vec3 centroid;
  for (size_t i = 1; i + 1 < light.vertices.size(); ++i) {
    double a = 0.5 * length(cross(light.vertices[i] - light.vertices[0],
                                  light.vertices[i + 1] - light.vertices[0]));
    area += a;
    centroid += (light.vertices[0] + light.vertices[i] + light.vertices[i + 1]) * (a / 3);
  }
  light.area = area;
  light.centroid = centroid / area;
  return light;
}

Light quad_light(Vec3 origin, Vec3 edge1, Vec3 edge2, Rgb radiance) {
  Light light =
      polygon_light({origin, origin + edge1, origin + edge1 + edge2, origin + edge2}, radiance);
  light.type = LightType::Quad;
  light.origin = origin;
  light.edge1 = edge1;
  light.edge2 = edge2;
  return light;
}

Scene single_light_scene(const Light& light) {
  Scene scene;
  scene.name = "test";
  Material white;
  white.name = "white";
  white.type = MaterialType::Lambert;
  white.albedo = {0.5, 0.6, 0.7};
  scene.materials.push_back(white);
  scene.lights.push_back(light);
  return scene;
}

std::vector<Light> test_lights() {
  return {
      // A rectangle (Ureña's spherical rectangle applies) facing down at height 1.
      quad_light({-0.3, 1, -0.2}, {0.8, 0, 0}, {0, 0, 0.5}, {4, 4, 4}),
      // A triangle and a pentagon, tilted, facing down-ish.
      polygon_light({{-0.5, 0.8, -0.4}, {0.6, 1.1, -0.3}, {0.1, 0.9, 0.6}}, {3, 3, 3}),
      polygon_light({{0.0, 1.0, -0.5},
                     {0.47, 1.0, -0.15},
                     {0.29, 1.0, 0.4},
                     {-0.29, 1.0, 0.4},
                     {-0.47, 1.0, -0.15}},
                    {2, 2, 2}),
  };
}

ShadingPoint receiver(const Scene& scene) {
  return {{0.1, 0, 0.2}, {0, 1, 0}, normalize(Vec3{0.3, 1, 0.1}), &scene.materials[0]};
}

Rgb closed_form(const Scene& scene, const ShadingPoint& sp) {
  const Light& light = scene.lights[0];
  return lambert_polygon_radiance(sp.material->albedo, light.radiance, sp.position, sp.normal,
                                  light.vertices, light.normal);
}

// Lights need the polygon winding the parser produces: check the test lights face the receiver.
TEST(DirectLighting, TestLightsFaceTheReceiver) {
  for (const Light& light : test_lights()) {
    Scene scene = single_light_scene(light);
    EXPECT_GT(closed_form(scene, receiver(scene)).x, 0.01);
  }
}

struct UnbiasedCase {
  const char* method;
  Pattern pattern;
};

class Unbiased : public ::testing::TestWithParam<UnbiasedCase> {};

TEST_P(Unbiased, ConvergesToLambertsClosedForm) {
  const UnbiasedCase& c = GetParam();
  for (const Light& light : test_lights()) {
    Scene scene = single_light_scene(light);
    DirectLighting direct(scene, parse_method(c.method));
    ShadingPoint sp = receiver(scene);
    NeverOccluded visibility;
    const int trials = 1'000'000 / direct.method().total_samples();
    double sum = 0, sum_sq = 0;
    for (int t = 0; t < trials; ++t) {
      StreamKey key{42, 0, uint32_t(t), 0};
      double value = direct.estimate(sp, visibility, c.pattern, key).y;
      ASSERT_TRUE(std::isfinite(value));
      sum += value;
      sum_sq += value * value;
    }
    double mean = sum / trials;
    double variance = std::max(0.0, (sum_sq / trials - mean * mean) * trials / (trials - 1.0));
    double standard_error = std::sqrt(variance / trials);
    double expected = closed_form(scene, sp).y;
    // Within 4 standard errors (plus a hair for the zero-variance cases).
    EXPECT_NEAR(mean, expected, 4 * standard_error + 1e-9 * expected)
        << c.method << " on a " << light.vertices.size() << "-gon: mean " << mean << " closed form "
        << expected << " standard error " << standard_error;
  }
}

INSTANTIATE_TEST_SUITE_P(
    EveryPointStrategyAndCombination, Unbiased,
    ::testing::Values(
        UnbiasedCase{"area", Pattern::Random}, UnbiasedCase{"sa", Pattern::Random},
        UnbiasedCase{"bsdf", Pattern::Random}, UnbiasedCase{"bsdf+sa", Pattern::Random},
        UnbiasedCase{"bsdf+sa/power", Pattern::Random},
        UnbiasedCase{"bsdf+sa/avg", Pattern::Random},
        UnbiasedCase{"area+2*sa/balance", Pattern::Random},
        UnbiasedCase{"area+bsdf+sa/power", Pattern::Random},
        UnbiasedCase{"4*sa", Pattern::Stratified}, UnbiasedCase{"4*area+4*bsdf", Pattern::Cmj},
        UnbiasedCase{"psa", Pattern::Random}, UnbiasedCase{"bsdf+psa/power", Pattern::Random},
        UnbiasedCase{"ltc", Pattern::Random}, UnbiasedCase{"ltc+bsdf+sa", Pattern::Random}),
    [](const auto& info) {
      std::string name = info.param.method;
      for (char& ch : name)
        if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
      return name + "_" + std::string(pattern_name(info.param.pattern) == "cmj" ? "cmj" : "p") +
             std::to_string(int(info.param.pattern));
    });

TEST(DirectLighting, MisWeightsSumToOneWhereAnyPdfIsNonzero) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0, 1);
  for (const char* method : {"bsdf+sa", "bsdf+sa/power", "bsdf+sa/avg", "area+3*sa+bsdf/balance",
                             "2*area+bsdf/power", "psa+bsdf", "psa+sa+area/power"}) {
    for (const Light& light : test_lights()) {
      Scene scene = single_light_scene(light);
      DirectLighting direct(scene, parse_method(method));
      ShadingPoint sp = receiver(scene);
      for (int i = 0; i < 2000; ++i) {
        // A point on the light: uniform over the polygon's fan.
        const auto& v = light.vertices;
        size_t tri = 1 + size_t(u(rng) * (v.size() - 2));
        double a = u(rng), b = u(rng);
        if (a + b > 1) a = 1 - a, b = 1 - b;
        Vec3 point = v[0] + (v[tri] - v[0]) * a + (v[tri + 1] - v[0]) * b;
        std::vector<double> w = direct.weights(sp, 0, point);
        double sum = 0;
        for (double wi : w) {
          EXPECT_GE(wi, 0.0);
          sum += wi;
        }
        EXPECT_NEAR(sum, 1.0, 1e-12) << method;
      }
    }
  }
}

TEST(DirectLighting, SameKeySameBits) {
  Scene scene = single_light_scene(test_lights()[0]);
  DirectLighting direct(scene, parse_method("bsdf+4*sa/power"));
  NeverOccluded visibility;
  ShadingPoint sp = receiver(scene);
  for (Pattern p : {Pattern::Random, Pattern::Stratified, Pattern::Cmj}) {
    StreamKey key{9, 17, 3, 0};
    Rgb a = direct.estimate(sp, visibility, p, key);
    Rgb b = direct.estimate(sp, visibility, p, key);
    EXPECT_EQ(a, b);
    key.pass = 4;
    EXPECT_FALSE(direct.estimate(sp, visibility, p, key) == a);
  }
}

TEST(DirectLighting, FiniteInDegenerateConfigurations) {
  NeverOccluded visibility;
  struct Case {
    const char* what;
    Light light;
    ShadingPoint point;
  };
  Scene base = single_light_scene(test_lights()[0]);
  const Material* white = &base.materials[0];
  std::vector<Case> cases{
      {"on the light's plane",
       quad_light({-0.5, 1, -0.5}, {1, 0, 0}, {0, 0, 1}, {1, 1, 1}),
       {{2, 1, 0}, {0, -1, 0}, {0, -1, 0}, white}},
      {"inside the light's plane, within the light",
       quad_light({-0.5, 1, -0.5}, {1, 0, 0}, {0, 0, 1}, {1, 1, 1}),
       {{0, 1, 0}, {0, -1, 0}, {0, -1, 0}, white}},
      {"behind the light",
       quad_light({-0.5, 1, -0.5}, {1, 0, 0}, {0, 0, 1}, {1, 1, 1}),
       {{0, 2, 0}, {0, -1, 0}, {0, -1, 0}, white}},
      {"1e-4 below the light",
       quad_light({-0.5, 1, -0.5}, {1, 0, 0}, {0, 0, 1}, {1, 1, 1}),
       {{0.1, 1 - 1e-4, 0.1}, {0, 1, 0}, {0, 1, 0}, white}},
      {"1 cm light at 40 m",
       quad_light({-0.005, 40, -0.005}, {0.01, 0, 0}, {0, 0, 0.01}, {1e4, 1e4, 1e4}),
       {{0, 0, 0}, {0, 1, 0}, {0, 1, 0}, white}},
      {"1 mm light at 40 m",
       quad_light({-0.0005, 40, -0.0005}, {0.001, 0, 0}, {0, 0, 0.001}, {1e6, 1e6, 1e6}),
       {{0, 0, 0}, {0, 1, 0}, {0, 1, 0}, white}},
      {"grazing normal",
       quad_light({-0.5, 1, -0.5}, {1, 0, 0}, {0, 0, 1}, {1, 1, 1}),
       {{0, 0, 0}, normalize(Vec3{1, 1e-9, 0}), normalize(Vec3{1, 1e-6, 0}), white}},
  };
  for (const Case& c : cases) {
    Scene scene = single_light_scene(c.light);
    ShadingPoint sp = c.point;
    sp.material = &scene.materials[0];
    for (const char* method :
         {"area", "sa", "bsdf", "psa", "bsdf+sa", "bsdf+sa/power", "area+sa/avg", "psa+bsdf"}) {
      DirectLighting direct(scene, parse_method(method));
      for (uint32_t t = 0; t < 2000; ++t) {
        Rgb value = direct.estimate(sp, visibility, Pattern::Random, {1, 0, t, 0});
        ASSERT_TRUE(is_finite(value)) << c.what << ", " << method;
        ASSERT_GE(value.x, 0.0) << c.what << ", " << method;
      }
    }
  }
}

TEST(DirectLighting, RefusesWhatIsNotAvailableWithAClearError) {
  Scene scene = single_light_scene(test_lights()[0]);
  // Peters' combinations run on one psa and one ltc term only (peters_combination_test.cpp).
  for (const char* method : {"bsdf+ltc/weighted", "psa+sa/clamped-optimal"}) {
    try {
      DirectLighting direct(scene, parse_method(method));
      ADD_FAILURE() << method << " accepted";
    } catch (const FormatError& e) {
      EXPECT_NE(std::string(e.what()).find("one psa term and one ltc term"), std::string::npos)
          << e.what();
    }
  }
}

}  // namespace
}  // namespace penumbra
