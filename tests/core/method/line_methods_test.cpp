// Line terms in the direct-lighting estimator (Salesin & Jarosz 2019): every line strategy and
// combination (MIS between line directions and with points; balance, power, avg, smooth-fixed,
// smooth) unbiased against Lambert's polygon formula (unoccluded, also with the light partly
// below the horizon) and against a converged point estimate (occluded); weights that sum to one
// wherever the integrand is nonzero, smoothing included and with only two strategies; finite
// values in degenerate configurations; clear refusals.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/lines/line_query.h"
#include "core/math/lambert_polygon.h"
#include "core/method/direct_lighting.h"
#include "tests/support/line_query_visibility.h"

namespace penumbra {
namespace {

Light quad_light(Vec3 origin, Vec3 edge1, Vec3 edge2, Rgb radiance) {
  Light light;
  light.type = LightType::Quad;
  light.origin = origin;
  light.edge1 = edge1;
  light.edge2 = edge2;
  light.radiance = radiance;
  light.vertices = {origin, origin + edge1, origin + edge1 + edge2, origin + edge2};
  light.normal = normalize(cross(edge1, edge2));
  light.area = length(cross(edge1, edge2));
  light.centroid = origin + 0.5 * (edge1 + edge2);
  return light;
}

// A rectangle facing down at height 1, and a triangle plus a bar between it and the floor.
Scene test_scene(bool occluders,
                 Light light = quad_light({-0.4, 1, -0.25}, {0.8, 0, 0}, {0, 0, 0.5}, {4, 4, 4})) {
  Scene scene;
  scene.name = "test";
  Material white;
  white.name = "white";
  white.albedo = {0.5, 0.6, 0.7};
  scene.materials.push_back(white);
  Material glossy;
  glossy.name = "glossy";
  glossy.type = MaterialType::Ggx;
  glossy.diffuse = {0.2, 0.2, 0.2};
  glossy.specular = {0.6, 0.6, 0.6};
  glossy.roughness = 0.2;
  scene.materials.push_back(glossy);
  scene.lights.push_back(light);
  if (occluders) {
    scene.positions = {{-0.2, 0.5, -0.2}, {0.25, 0.5, -0.15}, {0.0, 0.5, 0.2},
                       {-0.4, 0.7, 0.02}, {0.4, 0.7, 0.05},   {0.4, 0.7, 0.1}};
    scene.indices = {0, 1, 2, 3, 4, 5};
    scene.triangle_materials = {0, 0};
  }
  return scene;
}

ShadingPoint straight_receiver(const Scene& scene, int material = 0) {
  return {{0.05, 0, 0.02}, {0, 1, 0}, normalize(Vec3{0.3, 1, 0.1}), &scene.materials[material]};
}
// Tilted so that part of the light is below the horizon.
ShadingPoint tilted_receiver(const Scene& scene) {
  return {{0, 0, 0}, normalize(Vec3{1, 0.3, 0}), normalize(Vec3{0.3, 1, 0.1}), &scene.materials[0]};
}

struct Estimate {
  double mean = 0, standard_error = 0;
};

Estimate run(const Scene& scene, const char* method, const ShadingPoint& sp, Pattern pattern,
             int trials, int multiplier = 1) {
  DirectLighting direct(scene, parse_method(method));
  LineQuery query(scene);
  testing::LineQueryVisibility visibility(query);
  double sum = 0, sum_sq = 0;
  for (int t = 0; t < trials; ++t) {
    double value = direct.estimate(sp, visibility, pattern, {42, 0, uint32_t(t), 0}, multiplier).y;
    EXPECT_TRUE(std::isfinite(value));
    sum += value;
    sum_sq += value * value;
  }
  double mean = sum / trials;
  double variance = std::max(0.0, (sum_sq / trials - mean * mean) * trials / (trials - 1.0));
  return {mean, std::sqrt(variance / trials)};
}

const char* const kLineMethods[] = {
    "line-area:u",
    "line-area:v",
    "line-sa:u",
    "line-sa:v",
    "line-sa:u+line-sa:v",
    "line-area:u+line-area:v/power",
    "line-sa:u+line-sa:v/avg",
    "bsdf+line-sa:v",
    "bsdf+line-area:u/power",
    "sa+line-sa:u+line-area:v",
    "bsdf+line-sa:v/smooth-fixed",
    "bsdf+line-sa:v/smooth",
    "bsdf+line-sa:u+line-sa:v/smooth",
    "2*bsdf+line-area:v/smooth",
    "bsdf+area/smooth-fixed",
};

TEST(LineMethods, UnbiasedAgainstLambertsFormulaUnoccluded) {
  Scene scene = test_scene(false);
  const Light& light = scene.lights[0];
  for (bool tilted : {false, true}) {
    ShadingPoint sp = tilted ? tilted_receiver(scene) : straight_receiver(scene);
    double expected = lambert_polygon_radiance(sp.material->albedo, light.radiance, sp.position,
                                               sp.normal, light.vertices, light.normal)
                          .y;
    for (const char* method : kLineMethods) {
      Estimate e = run(scene, method, sp, Pattern::Random, 20000);
      EXPECT_NEAR(e.mean, expected, 4 * e.standard_error + 1e-9 * expected)
          << method << (tilted ? " (tilted)" : "") << " standard error " << e.standard_error;
    }
  }
}

TEST(LineMethods, UnbiasedAgainstAConvergedPointEstimateOccluded) {
  Scene scene = test_scene(true);
  for (int material : {0, 1}) {
    ShadingPoint sp = straight_receiver(scene, material);
    Estimate reference = run(scene, "bsdf+16*sa", sp, Pattern::Stratified, 20000);
    for (const char* method : kLineMethods) {
      Estimate e = run(scene, method, sp, Pattern::Random, 20000);
      double tolerance = 4 * std::hypot(e.standard_error, reference.standard_error);
      EXPECT_NEAR(e.mean, reference.mean, tolerance)
          << method << " on material " << material << ": standard error " << e.standard_error;
    }
  }
  // Stratified line offsets stay unbiased.
  ShadingPoint sp = straight_receiver(scene);
  Estimate reference = run(scene, "bsdf+16*sa", sp, Pattern::Stratified, 20000);
  for (const char* method :
       {"8*line-sa:v", "4*bsdf+4*line-sa:u/smooth", "4*line-area:u+4*line-area:v"}) {
    for (Pattern pattern : {Pattern::Stratified, Pattern::Cmj}) {
      Estimate e = run(scene, method, sp, pattern, 4000);
      EXPECT_NEAR(e.mean, reference.mean,
                  4 * std::hypot(e.standard_error, reference.standard_error))
          << method << " " << pattern_name(pattern);
    }
  }
}

TEST(LineMethods, WeightsSumToOneWhereTheIntegrandIsNonzero) {
  Scene scene = test_scene(true);
  LineQuery query(scene);
  const Light& light = scene.lights[0];
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> unit(0, 1);
  const char* const methods[] = {"bsdf+line-sa:v/smooth",
                                 "bsdf+line-sa:v/smooth-fixed",
                                 "bsdf+line-area:u/smooth",
                                 "line-sa:u+bsdf/smooth",
                                 "bsdf+line-sa:u+line-sa:v/smooth",
                                 "2*bsdf+bsdf/smooth",
                                 "bsdf+sa/smooth-fixed",
                                 "line-sa:u+line-sa:v",
                                 "line-area:u+line-sa:v/power",
                                 "bsdf+line-sa:v/avg",
                                 "sa+line-area:u+bsdf/balance"};
  for (const char* method : methods) {
    DirectLighting direct(scene, parse_method(method));
    for (bool tilted : {false, true}) {
      ShadingPoint sp = tilted ? tilted_receiver(scene) : straight_receiver(scene);
      int visible_points = 0;
      for (int i = 0; i < 3000; ++i) {
        // Uniform points, and points on or near the light's edges (where smoothing vanishes).
        double a = unit(rng), b = unit(rng);
        if (i % 4 == 1) a = 0;
        if (i % 4 == 2) b = 1e-9 * unit(rng);
        Vec3 point = light.origin + a * light.edge1 + b * light.edge2;
        bool nonzero =
            !query.occluded(sp.position, point) && dot(sp.normal, point - sp.position) > 0;
        std::vector<double> w = direct.weights(sp, 0, point, 1, &query);
        double sum = 0;
        for (double wi : w) {
          EXPECT_GE(wi, 0.0);
          EXPECT_LE(wi, 1.0);
          sum += wi;
        }
        if (nonzero) {
          ++visible_points;
          EXPECT_NEAR(sum, 1.0, 1e-12) << method << " at (" << a << ", " << b << ")";
        } else {
          // Hidden or below the horizon: the integrand is 0; weights sum to 1 or all vanish.
          EXPECT_TRUE(std::abs(sum - 1.0) <= 1e-12 || sum == 0.0) << method;
        }
      }
      EXPECT_GT(visible_points, 200);
    }
  }
}

TEST(LineMethods, SmoothingMovesWeightAwayFromTheBsdfAtEdges) {
  Scene scene = test_scene(false);
  LineQuery query(scene);
  const Light& light = scene.lights[0];
  ShadingPoint sp = straight_receiver(scene);
  DirectLighting plain(scene, parse_method("bsdf+line-sa:v"));
  DirectLighting smooth(scene, parse_method("bsdf+line-sa:v/smooth-fixed"));
  // On the edge: the BSDF's weight is 0 with smoothing; at the centre both agree.
  Vec3 edge = light.origin + 0.5 * light.edge1;
  EXPECT_GT(plain.weights(sp, 0, edge, 1, &query)[0], 0.0);
  EXPECT_EQ(smooth.weights(sp, 0, edge, 1, &query)[0], 0.0);
  Vec3 centre = light.centroid;
  EXPECT_NEAR(smooth.weights(sp, 0, centre, 1, &query)[0],
              plain.weights(sp, 0, centre, 1, &query)[0], 1e-12);
}

TEST(LineMethods, FiniteInDegenerateConfigurations) {
  struct Case {
    const char* what;
    Light light;
    ShadingPoint point;
  };
  std::vector<Case> cases{
      {"on the light's plane",
       quad_light({-0.5, 1, -0.5}, {1, 0, 0}, {0, 0, 1}, {1, 1, 1}),
       {{2, 1, 0}, {0, -1, 0}, {0, -1, 0}, nullptr}},
      {"behind the light",
       quad_light({-0.5, 1, -0.5}, {1, 0, 0}, {0, 0, 1}, {1, 1, 1}),
       {{0, 2, 0}, {0, -1, 0}, {0, -1, 0}, nullptr}},
      {"1e-4 below the light",
       quad_light({-0.5, 1, -0.5}, {1, 0, 0}, {0, 0, 1}, {1, 1, 1}),
       {{0.1, 1 - 1e-4, 0.1}, {0, 1, 0}, {0, 1, 0}, nullptr}},
      {"1 cm light at 40 m",
       quad_light({-0.005, 40, -0.005}, {0.01, 0, 0}, {0, 0, 0.01}, {1e4, 1e4, 1e4}),
       {{0, 0, 0}, {0, 1, 0}, {0, 1, 0}, nullptr}},
      {"1 mm light at 40 m",
       quad_light({-0.0005, 40, -0.0005}, {0.001, 0, 0}, {0, 0, 0.001}, {1e6, 1e6, 1e6}),
       {{0, 0, 0}, {0, 1, 0}, {0, 1, 0}, nullptr}},
      {"grazing normal",
       quad_light({-0.5, 1, -0.5}, {1, 0, 0}, {0, 0, 1}, {1, 1, 1}),
       {{0, 0, 0}, normalize(Vec3{1, 1e-9, 0}), normalize(Vec3{1, 1e-6, 0}), nullptr}},
      {"light edge parallel to the normal",
       quad_light({0.5, 0, -0.5}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}),
       {{0, 0, 0}, {0, 1, 0}, {0, 1, 0}, nullptr}},
  };
  for (const Case& c : cases) {
    Scene scene = test_scene(true, c.light);
    LineQuery query(scene);
    testing::LineQueryVisibility visibility(query);
    ShadingPoint sp = c.point;
    sp.material = &scene.materials[0];
    for (const char* method : kLineMethods) {
      DirectLighting direct(scene, parse_method(method));
      for (uint32_t t = 0; t < 300; ++t) {
        Rgb value = direct.estimate(sp, visibility, Pattern::Random, {1, 0, t, 0});
        ASSERT_TRUE(is_finite(value)) << c.what << ", " << method;
        ASSERT_GE(value.x, 0.0) << c.what << ", " << method;
      }
    }
  }
}

// The estimator's refusal of `method` on `scene` (its FormatError's message), or "" when it
// accepts the method.
std::string refusal(const Scene& scene, const char* method) {
  try {
    DirectLighting direct(scene, parse_method(method));
  } catch (const FormatError& e) {
    return e.what();
  }
  return "";
}

TEST(LineMethods, RefusesWhatIsNotDefinedWithAClearError) {
  Scene rectangle = test_scene(false);
  EXPECT_NE(refusal(rectangle, "line-sa:rand").find("no closed-form pdf"), std::string::npos);
  EXPECT_NE(refusal(rectangle, "bsdf+line-area:rand").find("use :u or :v"), std::string::npos);
  Scene parallelogram =
      test_scene(false, quad_light({-0.4, 1, -0.25}, {0.8, 0, 0}, {0.2, 0, 0.5}, {1, 1, 1}));
  EXPECT_NE(refusal(parallelogram, "line-sa:u").find("not perpendicular"), std::string::npos);
  EXPECT_EQ(refusal(parallelogram, "line-area:u+line-area:v/smooth"), "");
  Scene polygon = test_scene(false);
  polygon.lights[0].type = LightType::Polygon;
  EXPECT_NE(refusal(polygon, "line-area:u").find("is a polygon"), std::string::npos);
  EXPECT_NE(refusal(polygon, "bsdf+sa/smooth").find("is a polygon"), std::string::npos);
}

// Billen & Dutré's analytic lines through the estimator: alone (u, v, rand) and averaged with a
// point or line term; lambert and phong receivers only.
Scene bd16_scene(bool occluders) {
  Scene scene = test_scene(occluders);
  scene.materials.pop_back();  // the GGX material: line-bd16 refuses it
  Material phong;
  phong.name = "phong";
  phong.type = MaterialType::Phong;
  phong.kd = {0.3, 0.3, 0.3};
  phong.ks = {0.4, 0.4, 0.4};
  phong.exponent = 30;
  scene.materials.push_back(phong);
  return scene;
}

TEST(LineMethods, Bd16UnbiasedUnoccludedAndOccluded) {
  const char* const methods[] = {"line-bd16:u", "line-bd16:v", "4*line-bd16:rand",
                                 "line-bd16:u+line-sa:v/avg", "bsdf+2*line-bd16:rand/avg"};
  Scene open = bd16_scene(false);
  const Light& light = open.lights[0];
  ShadingPoint sp = straight_receiver(open);
  double expected = lambert_polygon_radiance(sp.material->albedo, light.radiance, sp.position,
                                             sp.normal, light.vertices, light.normal)
                        .y;
  for (const char* method : methods) {
    Estimate e = run(open, method, sp, Pattern::Random, 4000);
    EXPECT_NEAR(e.mean, expected, 4 * e.standard_error + 1e-9 * expected) << method;
  }
  Scene occluded = bd16_scene(true);
  for (int material : {0, 1}) {
    ShadingPoint p = straight_receiver(occluded, material);
    Estimate reference = run(occluded, "bsdf+16*sa", p, Pattern::Stratified, 20000);
    for (const char* method : methods) {
      for (Pattern pattern : {Pattern::Random, Pattern::Stratified}) {
        Estimate e = run(occluded, method, p, pattern, 4000);
        EXPECT_NEAR(e.mean, reference.mean,
                    4 * std::hypot(e.standard_error, reference.standard_error))
            << method << " on material " << material << ", " << pattern_name(pattern);
      }
    }
  }
}

TEST(LineMethods, Bd16RefusesMisAndUnsupportedMaterials) {
  Scene scene = bd16_scene(false);
  EXPECT_EQ(refusal(scene, "line-bd16:rand"), "");
  EXPECT_NE(refusal(scene, "bsdf+line-bd16:u").find("no pdf at a point"), std::string::npos);
  EXPECT_NE(refusal(scene, "line-sa:u+line-bd16:u/smooth").find("use it alone or with /avg"),
            std::string::npos);
  Scene glossy = test_scene(false);
  std::string why = refusal(glossy, "line-bd16:u");
  EXPECT_NE(why.find("line-bd16"), std::string::npos) << why;
  EXPECT_NE(why.find("glossy"), std::string::npos) << why;
}

TEST(LineMethods, NeedsALineQuery) {
  Scene scene = test_scene(false);
  DirectLighting direct(scene, parse_method("line-sa:u"));
  EXPECT_TRUE(direct.needs_line_query());
  class RaysOnly : public Visibility {
   public:
    bool occluded(const Vec3&, const Vec3&, const Vec3&) const override { return false; }
  } rays_only;
  EXPECT_THROW(direct.estimate(straight_receiver(scene), rays_only, Pattern::Random, {}),
               std::invalid_argument);
  EXPECT_FALSE(DirectLighting(scene, parse_method("bsdf+sa/smooth")).needs_line_query());
}

}  // namespace
}  // namespace penumbra
