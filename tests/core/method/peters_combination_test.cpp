// Peters' combinations in the estimator (`psa+ltc/weighted`, `psa+ltc/clamped-optimal`; Peters
// 2021 Sec. 4.2-4.3): zero variance through DirectLighting when the BSDF equals its LTC
// (Lambert: the identity LTC) and the light is unoccluded; unbiased against Lambert's closed
// form and, for a glossy ggx material with and without a partly occluding wall, against a
// converged `bsdf+sa` reference; weights that sum to one; finite values in degenerate
// configurations; clear errors for combinations it does not define.

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "core/math/lambert_polygon.h"
#include "core/method/direct_lighting.h"
#include "tests/core/strategies/test_support.h"

namespace penumbra {
namespace {

class NeverOccluded : public Visibility {
 public:
  bool occluded(const Vec3&, const Vec3&, const Vec3&) const override { return false; }
};

// An infinite wall in the plane x = wall_x between y = 0.05 and y = 0.9 (below the lights at
// y >= 1): it hides the light points on the far side of the wall from shading points on this
// side (the synthetic occluder of Peters Fig. 10).
class WallOccluder : public Visibility {
 public:
  explicit WallOccluder(double wall_x) : wall_x_(wall_x) {}
  bool occluded(const Vec3& from, const Vec3&, const Vec3& to) const override {
    double dx = to.x - from.x;
    if (dx == 0) return false;
    double t = (wall_x_ - from.x) / dx;
    if (!(t > 0 && t < 1)) return false;
    double y = from.y + t * (to.y - from.y);
    return y > 0.05 && y < 0.9;
  }

 private:
  double wall_x_;
};

std::vector<Light> test_lights() {
  return {
      test::quad_light({-0.3, 1, -0.2}, {0.8, 0, 0}, {0, 0, 0.5}, {4, 4, 4}),
      test::polygon_light({{-0.5, 0.8, -0.4}, {0.6, 1.1, -0.3}, {0.1, 0.9, 0.6}}, {3, 3, 3}),
      test::regular_polygon_light({0.1, 1.0, 0.0}, {0, -1, 0}, 0.5, 5),
  };
}

Scene scene_with(const Light& light, const Material& material) {
  Scene scene;
  scene.name = "test";
  scene.materials.push_back(material);
  scene.lights.push_back(light);
  return scene;
}

struct Statistics {
  Rgb mean, standard_error, relative_std;
};

Statistics run(const Scene& scene, const std::string& method, const ShadingPoint& sp,
               const Visibility& visibility, int trials, uint32_t seed, int multiplier = 1) {
  DirectLighting direct(scene, parse_method(method));
  Rgb sum, sum_sq;
  for (int t = 0; t < trials; ++t) {
    Rgb value =
        direct.estimate(sp, visibility, Pattern::Random, {seed, 0, uint32_t(t), 0}, multiplier);
    EXPECT_TRUE(is_finite(value)) << method;
    sum += value;
    sum_sq += value * value;
  }
  Statistics s;
  s.mean = sum / double(trials);
  for (int c = 0; c < 3; ++c) {
    double variance =
        std::max(0.0, sum_sq[c] / trials - s.mean[c] * s.mean[c]) * trials / (trials - 1.0);
    s.standard_error[c] = std::sqrt(variance / trials);
    s.relative_std[c] = s.mean[c] > 0 ? std::sqrt(variance) / s.mean[c] : 0.0;
  }
  return s;
}

ShadingPoint shading_point(const Scene& scene, const Vec3& position, const Vec3& wo) {
  return {position, {0, 1, 0}, normalize(wo), &scene.materials[0]};
}

// Sec. 4.2: with a Lambertian BSDF the LTC is the identity, lobe albedo 0: c_1 = 0, the weighted
// heuristic gives every ltc sample weight 0 and every psa sample weight 1, and psa is exact for
// a Lambertian integrand. Clamped optimal mixes in balance (the ltc samples then have p_1 = p_0
// and the same exact ratio f / p). Each estimate must then equal Lambert's closed form for every
// set of random numbers, whatever the counts and the multiplier (a wrong count or pdf breaks it).
TEST(PetersCombination, ZeroVarianceThroughTheEstimatorWhenTheBsdfIsItsLtc) {
  NeverOccluded visibility;
  for (const Light& light : test_lights()) {
    Scene scene = scene_with(light, test::lambert({0.5, 0.6, 0.7}));
    ShadingPoint sp = shading_point(scene, {0.1, 0, 0.2}, {0.3, 1, 0.1});
    Rgb expected = lambert_polygon_radiance(sp.material->albedo, light.radiance, sp.position,
                                            sp.normal, light.vertices, light.normal);
    ASSERT_GT(expected.x, 0.01);
    for (const char* method : {"psa+ltc/weighted", "psa+ltc/clamped-optimal", "ltc+3*psa/weighted",
                               "2*psa+ltc/clamped-optimal"}) {
      for (int multiplier : {1, 3}) {
        Statistics s = run(scene, method, sp, visibility, 300, 7, multiplier);
        for (int c = 0; c < 3; ++c) {
          EXPECT_LT(s.relative_std[c], 1e-6) << method << " x" << multiplier;
          EXPECT_NEAR(s.mean[c], expected[c], 1e-9 * expected[c]) << method;
        }
      }
    }
  }
}

// A glossy ggx plane (diffuse + specular, roughness 0.2) under each light, viewed so that the
// highlight falls on the light; without occlusion and behind a wall that hides part of the
// light. Reference: 64 * bsdf + 64 * sa (balance) over many trials. Both Peters combinations
// must agree within 5 combined standard errors.
TEST(PetersCombination, UnbiasedOnGlossyGgxAgainstAConvergedReference) {
  Material glossy = test::ggx({0.2, 0.25, 0.3}, {0.9, 0.6, 0.3}, 0.2);
  struct Case {
    const char* what;
    double wall_x;  // > 10: no wall
  };
  for (const Case& c : {Case{"unoccluded", 100.0}, Case{"wall at x = 0.25", 0.25}}) {
    NeverOccluded never;
    WallOccluder wall(c.wall_x);
    const Visibility& visibility = c.wall_x > 10 ? static_cast<const Visibility&>(never)
                                                 : static_cast<const Visibility&>(wall);
    for (const Light& light : test_lights()) {
      Scene scene = scene_with(light, glossy);
      ShadingPoint sp = shading_point(scene, {-0.2, 0, 0.05}, {-0.6, 1, -0.05});
      Statistics reference = run(scene, "64*bsdf+64*sa", sp, visibility, 2500, 3);
      for (const char* method :
           {"psa+ltc/weighted", "psa+ltc/clamped-optimal", "2*psa+ltc/clamped-optimal"}) {
        Statistics s = run(scene, method, sp, visibility, 40000, 5);
        for (int ch = 0; ch < 3; ++ch) {
          double tolerance = 5 * std::hypot(s.standard_error[ch], reference.standard_error[ch]);
          EXPECT_NEAR(s.mean[ch], reference.mean[ch], tolerance)
              << method << ", " << c.what << ", " << light.vertices.size() << "-gon, channel "
              << ch;
          // The reference's relative error is small enough for the test to mean something.
          EXPECT_LT(reference.standard_error[ch], 0.01 * reference.mean[ch]);
        }
      }
    }
  }
}

TEST(PetersCombination, WeightsSumToOne) {
  test::Rng rng(17);
  Material glossy = test::ggx({0.2, 0.25, 0.3}, {0.9, 0.6, 0.3}, 0.2);
  for (const char* method : {"psa+ltc/weighted", "3*psa+ltc/clamped-optimal"}) {
    for (const Light& light : test_lights()) {
      Scene scene = scene_with(light, glossy);
      DirectLighting direct(scene, parse_method(method));
      ShadingPoint sp = shading_point(scene, {-0.2, 0, 0.05}, {-0.6, 1, -0.05});
      for (int i = 0; i < 1000; ++i) {
        const auto& v = light.vertices;
        size_t tri = 1 + size_t(rng.uniform() * double(v.size() - 2));
        double a = rng.uniform(), b = rng.uniform();
        if (a + b > 1) a = 1 - a, b = 1 - b;
        Vec3 point = v[0] + (v[tri] - v[0]) * a + (v[tri + 1] - v[0]) * b;
        std::vector<double> w = direct.weights(sp, 0, point, 2);
        ASSERT_EQ(w.size(), 2u);
        EXPECT_GE(w[0], 0.0);
        EXPECT_GE(w[1], 0.0);
        EXPECT_NEAR(w[0] + w[1], 1.0, 1e-12) << method;
      }
    }
  }
}

TEST(PetersCombination, FiniteInDegenerateConfigurations) {
  NeverOccluded visibility;
  Material glossy = test::ggx({0.2, 0.25, 0.3}, {0.9, 0.6, 0.3}, 0.05);
  struct Case {
    const char* what;
    Light light;
    Vec3 position, normal, wo;
  };
  Light unit = test::quad_light({-0.5, 1, -0.5}, {1, 0, 0}, {0, 0, 1}, {1, 1, 1});
  std::vector<Case> cases{
      {"on the light's plane", unit, {2, 1, 0}, {0, -1, 0}, {0, -1, 0}},
      {"behind the light", unit, {0, 2, 0}, {0, -1, 0}, {0, -1, 0}},
      {"1e-4 below the light", unit, {0.1, 1 - 1e-4, 0.1}, {0, 1, 0}, {0, 1, 0}},
      {"1 cm light at 40 m",
       test::quad_light({-0.005, 40, -0.005}, {0.01, 0, 0}, {0, 0, 0.01}, {1e4, 1e4, 1e4}),
       {0, 0, 0},
       {0, 1, 0},
       {0, 1, 0}},
      {"1 mm light at 40 m, grazing view",
       test::quad_light({-0.0005, 40, -0.0005}, {0.001, 0, 0}, {0, 0, 0.001}, {1e6, 1e6, 1e6}),
       {0, 0, 0},
       {0, 1, 0},
       normalize(Vec3{1, 1e-3, 0})},
      {"grazing normal", unit, {0, 0, 0}, normalize(Vec3{1, 1e-9, 0}), normalize(Vec3{1, 1e-6, 0})},
  };
  for (const Case& c : cases) {
    Scene scene = scene_with(c.light, glossy);
    ShadingPoint sp{c.position, c.normal, c.wo, &scene.materials[0]};
    for (const char* method : {"psa+ltc/weighted", "psa+ltc/clamped-optimal"}) {
      DirectLighting direct(scene, parse_method(method));
      for (uint32_t t = 0; t < 2000; ++t) {
        Rgb value = direct.estimate(sp, visibility, Pattern::Random, {1, 0, t, 0});
        ASSERT_TRUE(is_finite(value)) << c.what << ", " << method;
        ASSERT_GE(value.x, 0.0) << c.what << ", " << method;
      }
    }
  }
}

TEST(PetersCombination, RefusesWhatItDoesNotDefineWithAClearError) {
  Scene polygon_scene = scene_with(test_lights()[2], test::lambert());
  auto expect_refusal = [](const Scene& scene, const char* method, const char* phrase) {
    try {
      DirectLighting direct(scene, parse_method(method));
      ADD_FAILURE() << method << " accepted";
    } catch (const FormatError& e) {
      EXPECT_NE(std::string(e.what()).find(phrase), std::string::npos) << e.what();
    }
  };
  for (const char* method : {"bsdf+ltc/weighted", "psa+sa/clamped-optimal", "psa/weighted",
                             "psa+ltc+bsdf/weighted", "psa+psa/clamped-optimal"})
    expect_refusal(polygon_scene, method, "one psa term and one ltc term");
  Scene disk_scene = scene_with(test::disk_light({0, 1, 0}, {0, -1, 0}, 0.3), test::lambert());
  expect_refusal(disk_scene, "psa+ltc/weighted", "disk");
  // The polygon samplers keep fixed arrays of 16 vertices; the scene format allows more.
  Scene many =
      scene_with(test::regular_polygon_light({0, 1, 0}, {0, -1, 0}, 0.4, 20), test::lambert());
  expect_refusal(many, "psa+ltc/clamped-optimal", "up to 16 vertices");
  expect_refusal(many, "psa", "up to 16 vertices");
  EXPECT_NO_THROW(DirectLighting(many, parse_method("sa")));
  // Accepted on quads and polygons.
  for (const Light& light : test_lights()) {
    Scene scene = scene_with(light, test::lambert());
    EXPECT_NO_THROW(DirectLighting(scene, parse_method("psa+ltc/weighted")));
    EXPECT_NO_THROW(DirectLighting(scene, parse_method("ltc+psa/clamped-optimal")));
  }
}

}  // namespace
}  // namespace penumbra
