// The polygon point strategies (ProjectedSolidAngleStrategy `psa`, SolidAngleStrategy `sa`:
// Peters' construction for polygons, Urena's spherical rectangle for rectangles): chi-square of
// their samples against their own area pdf, binned on the light's plane; pdf(sample) equal to the
// sample's pdf; the unoccluded Lambertian estimator (psa: relative standard deviation per sample
// below 1e-4; both: mean equal to Lambert's closed form); the one-sided emitter; disks refused by
// psa; tiny distant lights and edges parallel to the normal.

#include <gtest/gtest.h>

#include <iostream>
#include <random>
#include <stdexcept>
#include <vector>

#include "core/math/projected_solid_angle.h"
#include "core/strategies/psa_strategy.h"
#include "core/strategies/solid_angle_strategy.h"
#include "tests/support/polygon_test_util.h"

namespace penumbra {
namespace {

using polygon_test::light_facing;
using polygon_test::uniform;

ShadingPoint shading_point(const Vec3& position, const Vec3& normal) {
  ShadingPoint sp;
  sp.position = position;
  sp.normal = normalize(normal);
  sp.wo = sp.normal;
  return sp;
}

struct Configuration {
  const char* name;
  Light light;
  ShadingPoint sp;
};

std::vector<Configuration> configurations() {
  using polygon_test::quad_light;
  std::vector<Configuration> c;
  // Central: the normal points into the light (a ceiling quad above the point).
  c.push_back({"central quad", quad_light({-0.5, 1, -0.5}, {1, 0, 0}, {0, 0, 1}),
               shading_point({0.1, 0, 0.2}, {0, 1, 0})});
  // Decentral: the light off to the side of the normal.
  c.push_back({"decentral quad", quad_light({1, 1, -0.5}, {1, 0, 0}, {0, 0, 1}),
               shading_point({0, 0, 0}, {0, 1, 0})});
  // Decentral triangle, tilted.
  c.push_back({"tilted triangle",
               light_facing({{0.3, 1.2, -0.4}, {1.1, 0.9, 0.2}, {-0.2, 1.4, 0.5}}, {0, 0, 0}),
               shading_point({0, 0, 0}, {0.3, 1, -0.2})});
  // Pentagon, partly below the horizon of a tilted normal.
  c.push_back(
      {"pentagon crossing the horizon",
       light_facing({{1, 0.5, -1}, {1, 1.2, -0.6}, {1, 1.2, 0.6}, {1, 0.5, 1}, {1, -0.4, 0}},
                    {0, 0, 0}),
       shading_point({0, 0, 0}, {-0.3, 1, 0})});
  // Fig. 12: a light whose edges are parallel to the shading normal, crossing the horizon.
  c.push_back({"vertical quad (Fig. 12)", quad_light({1, -0.5, -0.5}, {0, 0, 1}, {0, 1.5, 0}),
               shading_point({0, 0, 0}, {0, 1, 0})});
  return c;
}

template <typename Strategy>
void expect_chi_square_passes(const Configuration& c, int count) {
  Strategy strategy(c.sp, c.light);
  std::vector<Vec3> polygon = c.light.vertices;
  auto result = polygon_test::chi_square_on_light(
      polygon,
      [&](const Vec2& u) -> std::optional<Vec3> {
        std::optional<LightPoint> p = strategy.sample(u);
        if (!p) return std::nullopt;
        return p->position;
      },
      [&](const Vec3& p) { return strategy.pdf(p); }, count, 16, 12345);
  EXPECT_EQ(result.missing, 0) << c.name;
  EXPECT_LT(result.statistic, result.critical)
      << Strategy::name() << " on " << c.name << ": chi-square " << result.statistic << " with "
      << result.dof << " degrees of freedom";
}

TEST(PolygonStrategies, ProjectedSolidAngleSamplesFollowTheirPdf) {
  for (const Configuration& c : configurations())
    expect_chi_square_passes<ProjectedSolidAngleStrategy>(c, 200000);
}

TEST(PolygonStrategies, SolidAngleSamplesFollowTheirPdf) {
  for (const Configuration& c : configurations())
    expect_chi_square_passes<SolidAngleStrategy>(c, 200000);
}

TEST(PolygonStrategies, ChiSquareDetectsAWrongPdf) {
  // The test must be able to fail: solid angle samples judged against the psa pdf.
  Configuration c = configurations()[1];
  SolidAngleStrategy sa(c.sp, c.light);
  ProjectedSolidAngleStrategy psa(c.sp, c.light);
  auto result = polygon_test::chi_square_on_light(
      c.light.vertices,
      [&](const Vec2& u) -> std::optional<Vec3> { return sa.sample(u)->position; },
      [&](const Vec3& p) { return psa.pdf(p); }, 200000, 16, 777);
  EXPECT_GT(result.statistic, result.critical);
}

template <typename Strategy>
void expect_pdf_of_sample_is_sample_pdf(uint64_t seed) {
  std::mt19937_64 rng(seed);
  int checked = 0;
  for (int trial = 0; trial < 300; ++trial) {
    int n = 3 + int(uniform(rng) * 6);
    Vec3 center = polygon_test::random_unit_vector(rng) * (0.2 + 5 * uniform(rng));
    std::vector<Vec3> vertices = polygon_test::random_convex_polygon(
        rng, n, center, polygon_test::random_unit_vector(rng), 0.1 + uniform(rng));
    Light light = polygon_test::polygon_light(vertices);
    ShadingPoint sp = shading_point({0, 0, 0}, polygon_test::random_unit_vector(rng));
    Strategy strategy(sp, light);
    for (int k = 0; k < 20; ++k) {
      std::optional<LightPoint> p = strategy.sample({uniform(rng), uniform(rng)});
      if (!p) continue;
      ASSERT_TRUE(std::isfinite(p->pdf_area));
      ASSERT_GT(p->pdf_area, 0.0);
      EXPECT_NEAR(strategy.pdf(p->position), p->pdf_area, 1e-9 * p->pdf_area) << trial;
      ++checked;
    }
  }
  EXPECT_GT(checked, 1000);
}

TEST(PolygonStrategies, PdfOfASampleIsTheSamplePdf) {
  expect_pdf_of_sample_is_sample_pdf<ProjectedSolidAngleStrategy>(41);
  expect_pdf_of_sample_is_sample_pdf<SolidAngleStrategy>(43);
}

// Unoccluded Lambertian light on a Lambertian point: L = Le * albedo / pi * projected solid
// angle (Lambert). Returns the mean and relative standard deviation per sample.
template <typename Strategy>
std::pair<double, double> lambertian_estimate(const Configuration& c, int count, uint64_t seed) {
  Strategy strategy(c.sp, c.light);
  const double radiance = 3.0, albedo = 0.7;
  std::mt19937_64 rng(seed);
  // Welford: sums of squares would cancel for the nearly constant psa estimates.
  double mean_running = 0, m2 = 0;
  for (int k = 0; k < count; ++k) {
    std::optional<LightPoint> p = strategy.sample({uniform(rng), uniform(rng)});
    double value = 0;
    if (p) {
      Vec3 to_light = p->position - c.sp.position;
      double r2 = length_squared(to_light);
      Vec3 wi = to_light / std::sqrt(r2);
      double cos_x = std::max(0.0, dot(c.sp.normal, wi));
      double cos_l = std::max(0.0, -dot(c.light.normal, wi));
      value = radiance * albedo / kPi * cos_x * cos_l / r2 / p->pdf_area;
    }
    double delta = value - mean_running;
    mean_running += delta / (k + 1);
    m2 += delta * (value - mean_running);
  }
  double mean = mean_running;
  double variance = m2 / count;
  return {mean, std::sqrt(variance) / mean};
}

TEST(PolygonStrategies, ProjectedSolidAngleHasNearZeroVarianceForLambertianLight) {
  for (const Configuration& c : configurations()) {
    auto [mean, relative_std] = lambertian_estimate<ProjectedSolidAngleStrategy>(c, 20000, 47);
    std::cout << "[ psa Lambertian ] " << c.name << ": relative standard deviation per sample "
              << relative_std << "\n";
    std::vector<Vec3> local;
    Frame frame = Frame::from_normal(c.sp.normal);
    for (const Vec3& v : c.light.vertices) local.push_back(frame.to_local(v - c.sp.position));
    double expected = 3.0 * 0.7 / kPi * projected_solid_angle(local);
    EXPECT_LT(relative_std, 1e-4) << c.name;
    EXPECT_NEAR(mean, expected, 1e-9 * expected) << c.name;
    // And against quadrature, independent of our closed form.
    double reference = 3.0 * 0.7 / kPi *
                       polygon_test::brute_force_projected_solid_angle(
                           c.light.vertices, c.sp.position, c.sp.normal, 1500);
    EXPECT_NEAR(mean, reference, 2e-3 * reference) << c.name;
  }
}

TEST(PolygonStrategies, SolidAngleEstimatorConvergesToLambert) {
  for (const Configuration& c : configurations()) {
    const int count = 200000;
    auto [mean, relative_std] = lambertian_estimate<SolidAngleStrategy>(c, count, 53);
    double reference = 3.0 * 0.7 / kPi *
                       polygon_test::brute_force_projected_solid_angle(
                           c.light.vertices, c.sp.position, c.sp.normal, 1500);
    // Five standard errors of the mean, plus the quadrature's own error.
    double tolerance = 5 * relative_std * mean / std::sqrt(double(count)) + 2e-3 * reference;
    EXPECT_NEAR(mean, reference, tolerance) << c.name;
    EXPECT_GT(relative_std, 1e-3) << c.name;  // solid angle sampling is not cosine-exact
  }
}

TEST(PolygonStrategies, PointsBehindTheLightGetNoSamples) {
  Light light = polygon_test::quad_light({-0.5, 1, -0.5}, {1, 0, 0}, {0, 0, 1});  // emits -y
  for (const ShadingPoint& sp : {shading_point({0, 2, 0}, {0, -1, 0}),            // behind
                                 shading_point({3, 1, 0}, {0, 1, 0})}) {          // in its plane
    ProjectedSolidAngleStrategy psa(sp, light);
    SolidAngleStrategy sa(sp, light);
    EXPECT_FALSE(psa.sample({0.4, 0.6}).has_value());
    EXPECT_FALSE(sa.sample({0.4, 0.6}).has_value());
    EXPECT_EQ(psa.pdf({0, 1, 0}), 0.0);
    EXPECT_EQ(sa.pdf({0, 1, 0}), 0.0);
  }
  // Lit, but the point lies outside the light: density 0 for psa (sa, like area, is asked only
  // for points on the light).
  ShadingPoint sp = shading_point({0, 0, 0}, {0, 1, 0});
  ProjectedSolidAngleStrategy psa(sp, light);
  SolidAngleStrategy sa(sp, light);
  EXPECT_EQ(psa.pdf({2, 1, 0}), 0.0);
  EXPECT_GT(psa.pdf({0, 1, 0}), 0.0);
  EXPECT_GT(sa.pdf({0, 1, 0}), 0.0);
}

TEST(PolygonStrategies, DisksAreRefused) {
  Light disk;
  disk.type = LightType::Disk;
  disk.center = {0, 1, 0};
  disk.normal = {0, -1, 0};
  disk.radius = 0.3;
  ShadingPoint sp = shading_point({0, 0, 0}, {0, 1, 0});
  EXPECT_THROW(ProjectedSolidAngleStrategy(sp, disk), std::invalid_argument);
  EXPECT_FALSE(is_polygon_light(disk));
}

// Fig. 7: a 1 cm and a 1 mm square light 40 m away: finite samples on the light with finite,
// consistent densities.
TEST(PolygonStrategies, TinyDistantLightsGiveFiniteSamples) {
  std::mt19937_64 rng(59);
  for (double side : {1e-2, 1e-3}) {
    for (int trial = 0; trial < 100; ++trial) {
      Vec3 position{0, 0, 0};
      Vec3 normal = normalize(Vec3{uniform(rng) - 0.5, 1.0, uniform(rng) - 0.5});
      Vec3 center{40 * (uniform(rng) - 0.5), 30, 40 * (uniform(rng) - 0.5)};
      Light light = polygon_test::quad_light(center, {side, 0, 0}, {0, 0, side});  // emits -y
      ShadingPoint sp = shading_point(position, normal);
      ProjectedSolidAngleStrategy psa(sp, light);
      SolidAngleStrategy sa(sp, light);
      for (int k = 0; k < 20; ++k) {
        Vec2 u{uniform(rng), uniform(rng)};
        for (std::optional<LightPoint> p : {psa.sample(u), sa.sample(u)}) {
          if (!p) continue;
          ASSERT_TRUE(is_finite(p->position));
          ASSERT_TRUE(std::isfinite(p->pdf_area));
          EXPECT_NEAR(p->position.y, 30.0, 1e-9);
          EXPECT_GT(p->position.x, center.x - 1e-6 * side);
          EXPECT_LT(p->position.x, center.x + side * (1 + 1e-6));
        }
        std::optional<LightPoint> p = psa.sample(u);
        if (normal.y > 0.2) {
          ASSERT_TRUE(p.has_value());
          EXPECT_NEAR(psa.pdf(p->position), p->pdf_area, 1e-6 * p->pdf_area);
        }
      }
    }
  }
}

}  // namespace
}  // namespace penumbra
