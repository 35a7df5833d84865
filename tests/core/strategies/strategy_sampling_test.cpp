// Every point strategy on every light shape it supports: the histogram of its samples on the
// light against its own area density (chi-square, significance 1e-4), the density it reports
// against pdf() at the sampled point (1e-9 relative), and, for strategies that never miss, the
// density integrating to one.

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "core/lights/light_geometry.h"
#include "core/strategies/area_strategy.h"
#include "core/strategies/bsdf_strategy.h"
#include "core/strategies/solid_angle_strategy.h"
#include "tests/core/strategies/light_chart.h"
#include "tests/core/strategies/test_support.h"

namespace penumbra {
namespace {

enum class Kind { Area, SolidAngle, Bsdf };

struct StrategyCase {
  std::string name;
  Kind kind;
  Light light;
  Vec3 position{0.1, 0.0, 0.15};
  Vec3 normal{0, 1, 0};
  Material material = test::lambert();
  bool may_miss = false;
};
void PrintTo(const StrategyCase& c, std::ostream* os) {
  *os << c.name;
}

// Lights above the default shading point, emitting downwards.
Light rectangle() {
  return test::quad_light({-0.3, 1, -0.2}, {0.6, 0, 0}, {0, 0, 0.5});
}
Light tilted_rectangle() {
  return test::quad_light({-0.3, 0.8, -0.2}, {0.6, 0.25, 0}, {0, 0, 0.5});
}
Light parallelogram() {
  return test::quad_light({-0.3, 1, -0.2}, {0.6, 0, 0}, {0.25, 0, 0.5});
}
Light triangle() {
  return test::down_polygon({{-0.4, 1, -0.2}, {0.3, 1.1, 0.3}, {0.4, 0.9, -0.35}});
}
Light pentagon() {
  return test::regular_polygon_light({0, 1, 0.1}, {0.1, -1, 0.05}, 0.4, 5);
}
Light disk() {
  return test::disk_light({0, 1, 0.1}, {0.1, -1, 0.2}, 0.3);
}

std::vector<StrategyCase> cases() {
  std::vector<StrategyCase> all;
  auto add = [&](std::string name, Kind kind, Light light) {
    StrategyCase c;
    c.name = std::move(name);
    c.kind = kind;
    c.light = std::move(light);
    c.may_miss =
        kind == Kind::Bsdf || (kind == Kind::SolidAngle && c.light.type == LightType::Disk);
    all.push_back(c);
    return &all.back();
  };
  add("area_rectangle", Kind::Area, rectangle());
  add("area_parallelogram", Kind::Area, parallelogram());
  add("area_triangle", Kind::Area, triangle());
  add("area_pentagon", Kind::Area, pentagon());
  add("area_disk", Kind::Area, disk());
  add("sa_rectangle", Kind::SolidAngle, rectangle());
  add("sa_tilted_rectangle", Kind::SolidAngle, tilted_rectangle());
  add("sa_rectangle_close", Kind::SolidAngle, rectangle())->position = {0.05, 0.8, 0.1};
  add("sa_rectangle_off_to_the_side", Kind::SolidAngle, rectangle())->position = {2.0, 0.5, -1.0};
  add("sa_parallelogram", Kind::SolidAngle, parallelogram());
  add("sa_triangle", Kind::SolidAngle, triangle());
  add("sa_pentagon", Kind::SolidAngle, pentagon());
  add("sa_pentagon_close", Kind::SolidAngle, pentagon())->position = {0.1, 0.7, 0.0};
  // 20 vertices: more fan triangles than the strategy caches.
  add("sa_20gon", Kind::SolidAngle,
      test::regular_polygon_light({0, 1, 0.1}, {0.1, -1, 0.05}, 0.4, 20));
  add("area_20gon", Kind::Area, test::regular_polygon_light({0, 1, 0.1}, {0.1, -1, 0.05}, 0.4, 20));
  add("sa_disk", Kind::SolidAngle, disk());
  add("sa_disk_oblique", Kind::SolidAngle, disk())->position = {1.5, 0.6, 0.3};
  // Within the radius of the centre: the hemisphere towards the disk bounds it.
  add("sa_disk_within_radius", Kind::SolidAngle, disk())->position =
      Vec3{0, 1, 0.1} + 0.15 * normalize(Vec3{0.1, -1, 0.2}) + Vec3{0.05, 0, 0};
  add("bsdf_lambert_rectangle", Kind::Bsdf, rectangle());
  add("bsdf_phong50_pentagon", Kind::Bsdf, pentagon())->material =
      test::phong({0.2, 0.2, 0.2}, {0.7, 0.7, 0.7}, 50);
  add("bsdf_ggx05_disk", Kind::Bsdf, disk())->material =
      test::ggx({0.1, 0.1, 0.1}, {0.9, 0.9, 0.9}, 0.5);
  add("bsdf_ggx005_triangle", Kind::Bsdf, triangle())->material =
      test::ggx({0.05, 0.05, 0.05}, {0.9, 0.9, 0.9}, 0.05);
  add("bsdf_phong1_parallelogram", Kind::Bsdf, parallelogram())->material =
      test::phong({0.5, 0.5, 0.5}, {0.4, 0.4, 0.4}, 1);
  // Glossy lobes aimed at the light: the default wo is chosen so the mirror direction hits it.
  for (auto& c : all)
    if (c.kind == Kind::Bsdf) c.position = {0.3, 0.0, 0.3};
  return all;
}

Vec3 wo_towards_mirror_of(const StrategyCase& c) {
  // wo = mirror of the direction to the light's centroid, so glossy lobes see the light.
  Vec3 to_light = normalize(c.light.centroid - c.position);
  return normalize(2.0 * dot(to_light, c.normal) * c.normal - to_light);
}

class StrategySampling : public ::testing::TestWithParam<StrategyCase> {};

template <class Strategy>
void check_strategy(const StrategyCase& c) {
  ShadingPoint sp{c.position, c.normal, wo_towards_mirror_of(c), &c.material};
  Strategy strategy(sp, c.light);
  test::LightChart chart(c.light);
  const int samples = 200000;
  std::vector<double> observed(chart.bin_count() + 1, 0.0);
  test::Rng rng(42);
  double worst_mismatch = 0;
  for (int i = 0; i < samples; ++i) {
    auto s = strategy.sample(rng.uniform2());
    if (!s) {
      observed.back() += 1;
      continue;
    }
    ASSERT_TRUE(light_contains(c.light, s->position)) << c.name << " sample " << i;
    ASSERT_GT(s->pdf_area, 0.0);
    worst_mismatch =
        std::max(worst_mismatch, test::relative_difference(s->pdf_area, strategy.pdf(s->position)));
    observed[chart.bin(s->position)] += 1;
  }
  EXPECT_LE(worst_mismatch, 1e-9) << "sample.pdf_area differs from pdf(sample.position)";
  std::vector<double> expected = chart.integrate([&](const Vec3& p) { return strategy.pdf(p); });
  double total = 0;
  for (double& e : expected) {
    total += e;
    e *= samples;
  }
  if (!c.may_miss) {
    EXPECT_NEAR(total, 1.0, 2e-3) << "the density does not integrate to one";
    EXPECT_EQ(observed.back(), 0.0) << "a strategy that never misses returned no sample";
  } else {
    EXPECT_LE(total, 1.0 + 2e-3);
  }
  expected.push_back(std::max(0.0, (1.0 - total) * samples));
  auto result = test::chi_square_test(observed, expected);
  EXPECT_TRUE(result.passed) << c.name << ": " << result.summary();
}

TEST_P(StrategySampling, HistogramMatchesDensity) {
  const StrategyCase& c = GetParam();
  switch (c.kind) {
    case Kind::Area:
      check_strategy<AreaStrategy>(c);
      break;
    case Kind::SolidAngle:
      check_strategy<SolidAngleStrategy>(c);
      break;
    case Kind::Bsdf:
      check_strategy<BsdfStrategy>(c);
      break;
  }
}

INSTANTIATE_TEST_SUITE_P(Strategies, StrategySampling, ::testing::ValuesIn(cases()),
                         [](const auto& info) { return info.param.name; });

// E[1 / p_area] = area for a strategy that covers the whole light: a check of the density's
// normalization where histograms are impractical (a point 1e-3 from a large light, a tiny light
// far away), to 4 standard errors.
template <class Strategy>
void check_area_estimate(const Light& light, const Vec3& position, uint64_t seed) {
  Material m = test::lambert();
  ShadingPoint sp{position, {0, 1, 0}, {0, 1, 0}, &m};
  Strategy strategy(sp, light);
  test::Rng rng(seed);
  const int samples = 400000;
  double sum = 0, sum_sq = 0;
  for (int i = 0; i < samples; ++i) {
    auto s = strategy.sample(rng.uniform2());
    double value = s ? 1.0 / s->pdf_area : 0.0;
    ASSERT_TRUE(std::isfinite(value));
    sum += value;
    sum_sq += value * value;
  }
  double mean = sum / samples;
  double se = std::sqrt(std::max(0.0, sum_sq / samples - mean * mean) / (samples - 1));
  EXPECT_NEAR(mean, light.area, 4 * se + 1e-9 * light.area)
      << "position " << position.x << " " << position.y << " " << position.z;
}

TEST(SolidAngleNormalization, CloseAndFarConfigurations) {
  Light rect = rectangle(), pent = pentagon(), d = disk();
  Vec3 below_rect = rect.centroid + 1e-3 * rect.normal + Vec3{0.1, 0, 0.05};
  check_area_estimate<SolidAngleStrategy>(rect, below_rect, 1);
  check_area_estimate<SolidAngleStrategy>(pent, pent.centroid + 1e-3 * pent.normal, 2);
  check_area_estimate<SolidAngleStrategy>(d, d.centroid + 1e-2 * d.normal, 3);
  // A 1 cm light 40 m away.
  Light tiny = test::quad_light({-0.005, 40, -0.005}, {0.01, 0, 0}, {0, 0, 0.01});
  check_area_estimate<SolidAngleStrategy>(tiny, {0.3, 0, 0.2}, 4);
  Light tiny_triangle = test::down_polygon({{0, 40, 0}, {0.01, 40, 0}, {0, 40, 0.01}});
  check_area_estimate<SolidAngleStrategy>(tiny_triangle, {0.3, 0, 0.2}, 5);
}

}  // namespace
}  // namespace penumbra
