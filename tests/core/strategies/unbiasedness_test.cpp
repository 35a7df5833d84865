// Unbiasedness of every point strategy: the mean of 10^6 one-sample estimates of the direct
// radiance at a Lambertian point under an unoccluded constant light, against Lambert's closed
// form (core/math/lambert_polygon.h; on-axis disk: albedo Le R^2 / (R^2 + h^2)), within 4
// standard errors.

#include <gtest/gtest.h>

#include <vector>

#include "core/lights/light_geometry.h"
#include "core/materials/bsdf.h"
#include "core/math/lambert_polygon.h"
#include "core/strategies/area_strategy.h"
#include "core/strategies/bsdf_strategy.h"
#include "core/strategies/solid_angle_strategy.h"
#include "tests/core/strategies/test_support.h"

namespace penumbra {
namespace {

struct Estimate {
  double mean = 0, standard_error = 0;
};

// The one-sample estimator f Le cos_x cos_l / (r^2 p_area), green channel.
template <class Strategy>
Estimate estimate(const ShadingPoint& sp, const Light& light, int samples, uint64_t seed) {
  Strategy strategy(sp, light);
  test::Rng rng(seed);
  double sum = 0, sum_sq = 0;
  for (int i = 0; i < samples; ++i) {
    double value = 0;
    if (auto s = strategy.sample(rng.uniform2())) {
      Vec3 d = s->position - sp.position;
      double r2 = length_squared(d);
      Vec3 wi = d / std::sqrt(r2);
      double cos_x = std::max(0.0, dot(sp.normal, wi));
      double cos_l = std::abs(dot(light.normal, wi));
      Rgb le = emitted_radiance(light, s->position, -wi);
      Rgb f = eval_bsdf(*sp.material, sp.normal, sp.wo, wi);
      value = f.y * le.y * cos_x * cos_l / (r2 * s->pdf_area);
    }
    sum += value;
    sum_sq += value * value;
  }
  Estimate e;
  e.mean = sum / samples;
  e.standard_error = std::sqrt(std::max(0.0, sum_sq / samples - e.mean * e.mean) / (samples - 1));
  return e;
}

struct UnbiasednessCase {
  std::string name;
  Light light;
  Vec3 position{0.1, 0, 0.15};
  Vec3 normal{0, 1, 0};
};
void PrintTo(const UnbiasednessCase& c, std::ostream* os) {
  *os << c.name;
}

std::vector<UnbiasednessCase> cases() {
  Rgb le{2, 3, 4};
  std::vector<UnbiasednessCase> all;
  all.push_back({"quad", test::quad_light({-0.3, 1, -0.2}, {0.6, 0, 0}, {0, 0, 0.5}, le)});
  all.push_back(
      {"parallelogram", test::quad_light({-0.3, 1, -0.2}, {0.6, 0, 0}, {0.3, 0.1, 0.5}, le)});
  Light triangle = test::down_polygon({{-0.4, 1, -0.2}, {0.3, 1.1, 0.3}, {0.4, 0.9, -0.35}});
  triangle.radiance = le;
  all.push_back({"triangle", triangle});
  Light pentagon = test::regular_polygon_light({0, 1, 0.1}, {0.1, -1, 0.05}, 0.4, 5);
  pentagon.radiance = le;
  all.push_back({"pentagon", pentagon});
  // The receiver's horizon cuts the pentagon: part of the light is below it.
  UnbiasednessCase crossing{"pentagon_crossing_horizon", pentagon};
  crossing.position = {0.0, 0.9, 0.1};
  crossing.normal = normalize(Vec3{0.2, 1, 0.1});
  all.push_back(crossing);
  // A close light (0.05 below a rectangle).
  UnbiasednessCase close{"quad_close", all[0].light};
  close.position = {0.05, 0.95, 0.1};
  all.push_back(close);
  return all;
}

class Unbiasedness : public ::testing::TestWithParam<UnbiasednessCase> {};

TEST_P(Unbiasedness, EveryStrategyMatchesLambertsClosedForm) {
  const UnbiasednessCase& c = GetParam();
  Material m = test::lambert({0.8, 0.6, 0.4});
  ShadingPoint sp{c.position, c.normal, c.normal, &m};
  double reference = lambert_polygon_radiance(m.albedo, c.light.radiance, c.position, c.normal,
                                              c.light.vertices, c.light.normal)
                         .y;
  ASSERT_GT(reference, 0.0);
  const int samples = 1000000;
  Estimate area = estimate<AreaStrategy>(sp, c.light, samples, 1);
  Estimate sa = estimate<SolidAngleStrategy>(sp, c.light, samples, 2);
  Estimate bsdf = estimate<BsdfStrategy>(sp, c.light, samples, 3);
  for (auto [name, e] : {std::pair{"area", area}, std::pair{"sa", sa}, std::pair{"bsdf", bsdf}}) {
    EXPECT_NEAR(e.mean, reference, 4 * e.standard_error + 1e-12 * reference)
        << c.name << " " << name << ": standard error " << e.standard_error;
    EXPECT_GT(e.standard_error, 0.0) << name;
    EXPECT_LT(e.standard_error, 0.05 * reference) << name << ": too few samples to mean anything";
  }
}

INSTANTIATE_TEST_SUITE_P(Lights, Unbiasedness, ::testing::ValuesIn(cases()),
                         [](const auto& info) { return info.param.name; });

TEST(UnbiasednessDisk, OnAxisClosedForm) {
  // Receiver facing a disk on its axis at height h: F = R^2 / (R^2 + h^2).
  double radius = 0.3, h = 0.7;
  Light disk = test::disk_light({0.1, h, 0.15}, {0, -1, 0}, radius, {2, 3, 4});
  Material m = test::lambert({0.8, 0.6, 0.4});
  ShadingPoint sp{{0.1, 0, 0.15}, {0, 1, 0}, {0, 1, 0}, &m};
  double reference = 0.6 * 3 * radius * radius / (radius * radius + h * h);
  const int samples = 1000000;
  Estimate area = estimate<AreaStrategy>(sp, disk, samples, 4);
  Estimate sa = estimate<SolidAngleStrategy>(sp, disk, samples, 5);
  Estimate bsdf = estimate<BsdfStrategy>(sp, disk, samples, 6);
  for (auto [name, e] : {std::pair{"area", area}, std::pair{"sa", sa}, std::pair{"bsdf", bsdf}})
    EXPECT_NEAR(e.mean, reference, 4 * e.standard_error) << name;
}

}  // namespace
}  // namespace penumbra
