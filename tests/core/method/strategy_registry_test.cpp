// The strategy registry (core/strategies/registry.h): a strategy is one row, and every row is
// reachable from the method grammar by its name, round-trips through the canonical text, passes
// the method check on a scene it supports, and, run alone by the estimator on an unoccluded
// rectangular light over a Lambertian receiver, converges to Lambert's closed form (within 4
// standard errors). A new row is covered by these tests without editing them.

#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <string>

#include "core/lines/line_query.h"
#include "core/math/lambert_polygon.h"
#include "core/method/direct_lighting.h"
#include "core/method/method_check.h"
#include "core/strategies/registered_strategies.h"
#include "tests/support/line_query_visibility.h"

namespace penumbra {
namespace {

// A rectangle facing down at height 1 over a Lambertian floor: every strategy runs on it.
Scene rectangle_scene() {
  Scene scene;
  scene.name = "registry";
  Material white;
  white.name = "white";
  white.albedo = {0.5, 0.6, 0.7};
  scene.materials.push_back(white);
  Light light;
  light.type = LightType::Quad;
  light.origin = {-0.4, 1, -0.25};
  light.edge1 = {0.8, 0, 0};
  light.edge2 = {0, 0, 0.5};
  light.radiance = {4, 4, 4};
  light.vertices = {light.origin, light.origin + light.edge1,
                    light.origin + light.edge1 + light.edge2, light.origin + light.edge2};
  light.normal = normalize(cross(light.edge1, light.edge2));
  light.area = length(cross(light.edge1, light.edge2));
  light.centroid = light.origin + 0.5 * (light.edge1 + light.edge2);
  scene.lights.push_back(light);
  return scene;
}

// The term of a row alone, in the grammar (line strategies along edge1).
std::string single_term(const StrategyInfo& info) {
  return std::string(info.name) + (info.family == StrategyFamily::Point ? "" : ":u");
}

TEST(StrategyRegistry, EveryRowIsReachableByItsOwnName) {
  std::set<std::string_view> names;
  const auto infos = registered_strategy_infos();
  ASSERT_EQ(infos.size(), RegisteredStrategies::size);
  for (size_t id = 0; id < infos.size(); ++id) {
    EXPECT_TRUE(names.insert(infos[id].name).second) << "two rows named " << infos[id].name;
    ASSERT_TRUE(find_strategy(infos[id].name).has_value()) << infos[id].name;
    EXPECT_EQ(*find_strategy(infos[id].name), StrategyId(id));
    EXPECT_EQ(strategy_name(StrategyId(id)), infos[id].name);
  }
  EXPECT_FALSE(find_strategy("no-such-strategy").has_value());
  // The compile-time ids agree with the rows' names.
  EXPECT_EQ(strategy_name(strategy_id<BsdfStrategy>), "bsdf");
  EXPECT_EQ(strategy_name(strategy_id<LineBd16Strategy>), "line-bd16");
}

TEST(StrategyRegistry, EveryRowRoundTripsThroughTheMethodGrammar) {
  const auto infos = registered_strategy_infos();
  for (size_t id = 0; id < infos.size(); ++id) {
    const std::string text = "2*" + single_term(infos[id]);
    MethodSpec method = parse_method(text);
    ASSERT_EQ(method.terms.size(), 1u);
    EXPECT_EQ(method.terms[0].strategy, StrategyId(id)) << text;
    EXPECT_EQ(method.terms[0].count, 2);
    EXPECT_EQ(to_string(method), text);
    EXPECT_EQ(parse_method(to_string(method)), method) << text;
    // Only line strategies take a direction.
    if (infos[id].family == StrategyFamily::Point) {
      EXPECT_THROW(parse_method(std::string(infos[id].name) + ":u"), FormatError);
    }
  }
}

TEST(StrategyRegistry, EveryRowRunsOnASceneItSupportsAndConvergesToLambert) {
  const Scene scene = rectangle_scene();
  LineQuery query(scene);
  testing::LineQueryVisibility visibility(query);
  const ShadingPoint sp{
      {0.05, 0, 0.02}, {0, 1, 0}, normalize(Vec3{0.3, 1, 0.1}), &scene.materials[0]};
  const Light& light = scene.lights[0];
  const double expected = lambert_polygon_radiance(sp.material->albedo, light.radiance, sp.position,
                                                   sp.normal, light.vertices, light.normal)
                              .y;
  ASSERT_GT(expected, 0.01);
  for (const StrategyInfo& info : registered_strategy_infos()) {
    const std::string text = single_term(info);
    MethodSpec method = parse_method(text);
    EXPECT_NO_THROW(check_method_runs_on(scene, method)) << text;
    DirectLighting direct(scene, method);
    const int trials = 20000;
    double sum = 0, sum_sq = 0;
    for (int t = 0; t < trials; ++t) {
      double value = direct.estimate(sp, visibility, Pattern::Random, {7, 0, uint32_t(t), 0}).y;
      ASSERT_TRUE(std::isfinite(value)) << text;
      sum += value;
      sum_sq += value * value;
    }
    double mean = sum / trials;
    double variance = std::max(0.0, (sum_sq / trials - mean * mean) * trials / (trials - 1.0));
    double standard_error = std::sqrt(variance / trials);
    EXPECT_NEAR(mean, expected, 4 * standard_error + 1e-9 * expected)
        << text << ": mean " << mean << ", Lambert " << expected;
  }
}

}  // namespace
}  // namespace penumbra
