// line-bd16 (Billen & Dutré 2016): offset sampling against its density (chi-square, with fine
// bins at the breakpoints), unbiasedness against Lambert's polygon formula (unoccluded quad and
// triangle, directions u, v and rand), against an area-sampled reference with brute-force
// visibility (occluded), variance reduction of stratified offsets, refusals, and finite values
// in degenerate configurations.

#include "core/lines/bd16_estimator.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "core/math/lambert_polygon.h"
#include "core/scene/light_setup.h"

namespace penumbra {
namespace {

// ---------------------------------------------------------------------------------------------
// Offset sampling.

// Chi-square of the offsets sampled from `distribution` against its pdf: bins uniform over the
// range plus narrow bins on both sides of every interior breakpoint; expected counts integrate
// the pdf exactly (it is linear between breakpoints: trapezoids on bins split at breakpoints).
void check_offset_histogram(const Light& light, const Vec3& direction, uint64_t seed) {
  LineOffsetDistribution distribution(light, direction);
  double lo = distribution.min_offset(), hi = distribution.max_offset();
  ASSERT_LT(lo, hi);
  std::vector<double> edges;
  constexpr int kUniformBins = 40;
  for (int i = 0; i <= kUniformBins; ++i) edges.push_back(lo + (hi - lo) * i / kUniformBins);
  for (double breakpoint : distribution.breakpoints()) {
    for (double delta : {-0.01, -0.003, -0.001, 0.001, 0.003, 0.01}) {
      double edge = breakpoint + delta * (hi - lo);
      if (edge > lo && edge < hi) edges.push_back(edge);
    }
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end(),
                          [&](double a, double b) { return b - a < 1e-9 * (hi - lo); }),
              edges.end());
  size_t bins = edges.size() - 1;

  // Expected probability per bin: trapezoid rule on sub-pieces split at the breakpoints (exact).
  std::vector<double> expected(bins, 0.0);
  for (size_t i = 0; i < bins; ++i) {
    std::vector<double> points{edges[i], edges[i + 1]};
    for (double breakpoint : distribution.breakpoints()) {
      if (breakpoint > edges[i] && breakpoint < edges[i + 1]) points.push_back(breakpoint);
    }
    std::sort(points.begin(), points.end());
    for (size_t k = 0; k + 1 < points.size(); ++k) {
      double a = points[k], b = points[k + 1];
      // Evaluate inside the piece (the pdf is continuous, but avoid edge rounding).
      double pa = distribution.pdf(a + 1e-12 * (b - a)), pb = distribution.pdf(b - 1e-12 * (b - a));
      expected[i] += 0.5 * (pa + pb) * (b - a);
    }
  }
  double total_probability = 0;
  for (double p : expected) total_probability += p;
  EXPECT_NEAR(total_probability, 1.0, 1e-9);

  constexpr int kSamples = 400000;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::vector<double> counts(bins, 0.0);
  for (int s = 0; s < kSamples; ++s) {
    auto line = distribution.sample(uniform(rng));
    ASSERT_TRUE(line.has_value());
    // The sampler's pdf is the density pdf_of_offset reports at the same offset.
    if (s < 2000) {
      EXPECT_NEAR(line->pdf, pdf_of_offset(light, direction, line->offset), 1e-9 * line->pdf);
      EXPECT_NEAR(length(line->b - line->a), line->pdf * light.area, 1e-9 * std::sqrt(light.area));
    }
    size_t bin = static_cast<size_t>(std::upper_bound(edges.begin(), edges.end(), line->offset) -
                                     edges.begin());
    bin = std::clamp<size_t>(bin, 1, bins) - 1;
    counts[bin] += 1;
  }
  double chi_square = 0;
  int degrees = -1;
  for (size_t i = 0; i < bins; ++i) {
    double want = expected[i] * kSamples;
    if (want < 5) {
      EXPECT_LE(counts[i], 5 + 5 * std::sqrt(want + 1)) << "bin " << i;
      continue;
    }
    chi_square += (counts[i] - want) * (counts[i] - want) / want;
    ++degrees;
  }
  // 5 standard deviations above the mean of the chi-square distribution.
  EXPECT_LT(chi_square, degrees + 5.0 * std::sqrt(2.0 * degrees))
      << "degrees of freedom " << degrees;
}

TEST(Bd16OffsetSampling, TriangleAlongItsEdgesAndRandomDirections) {
  Light triangle = make_polygon_light({{0, 0, 0}, {2, 0, 0}, {0.5, 1.5, 0}}, {1, 1, 1});
  check_offset_histogram(triangle, bd16_line_direction(triangle, Bd16Direction::U, {}), 1);
  check_offset_histogram(triangle, bd16_line_direction(triangle, Bd16Direction::V, {}), 2);
  for (double angle : {0.1, 0.37, 0.8}) {
    check_offset_histogram(triangle,
                           bd16_line_direction(triangle, Bd16Direction::Random, {angle, 0}), 3);
  }
}

TEST(Bd16OffsetSampling, RotatedParallelogramIsTrapezoidal) {
  Light quad = make_quad_light({0, 0, 0}, {2, 0, 0}, {0.6, 1, 0}, {1, 1, 1});
  for (double angle : {0.13, 0.25, 0.61, 0.9}) {
    Vec3 direction = bd16_line_direction(quad, Bd16Direction::Random, {angle, 0});
    LineOffsetDistribution distribution(quad, direction);
    EXPECT_EQ(distribution.breakpoints().size(), 4u);
    check_offset_histogram(quad, direction, 4);
  }
  // Along an edge the density is constant: l(w) = area / width.
  Vec3 along = bd16_line_direction(quad, Bd16Direction::U, {});
  LineOffsetDistribution constant(quad, along);
  double width = constant.max_offset() - constant.min_offset();
  for (double f : {0.01, 0.3, 0.99}) {
    EXPECT_NEAR(constant.pdf(constant.min_offset() + f * width), 1.0 / width, 1e-9 / width);
  }
  check_offset_histogram(quad, along, 5);
}

TEST(Bd16OffsetSampling, ConvexPentagon) {
  Light pentagon =
      make_polygon_light({{0, 0, 1}, {2, 0, 1}, {2.5, 1, 1}, {1, 2, 1}, {-0.5, 1, 1}}, {1, 1, 1});
  check_offset_histogram(pentagon, bd16_line_direction(pentagon, Bd16Direction::Random, {0.3, 0}),
                         6);
}

// ---------------------------------------------------------------------------------------------
// Estimates.

struct ShadingPoint {
  Vec3 x, n, wo;
};

Material lambert_material() {
  Material m;
  m.name = "white";
  m.albedo = {0.7, 0.5, 0.3};
  return m;
}

Material phong_material(double exponent) {
  Material m;
  m.name = "shiny";
  m.type = MaterialType::Phong;
  m.kd = {0.2, 0.2, 0.2};
  m.ks = {0.6, 0.5, 0.4};
  m.exponent = exponent;
  return m;
}

struct Statistics {
  Rgb mean{0, 0, 0};
  double standard_error = 0;  // of the red channel's mean
};

// Mean of `trials` estimates, each with its own random direction_u and one random offset.
template <typename Estimate>
Statistics sample_mean(int trials, uint64_t seed, Estimate estimate) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  Rgb sum{0, 0, 0};
  double sum_squares = 0;
  for (int i = 0; i < trials; ++i) {
    Vec2 direction_u{uniform(rng), uniform(rng)};
    Rgb value = estimate(uniform(rng), direction_u);
    EXPECT_TRUE(is_finite(value));
    sum += value;
    sum_squares += value.x * value.x;
  }
  Statistics stats;
  stats.mean = sum / trials;
  double variance = std::max(0.0, sum_squares / trials - stats.mean.x * stats.mean.x);
  stats.standard_error = std::sqrt(variance / trials);
  return stats;
}

void check_unbiased_lambert(const Light& light, const ShadingPoint& p) {
  Material material = lambert_material();
  Rgb want = lambert_polygon_radiance(material.albedo, light.radiance, p.x, p.n, light.vertices,
                                      light.normal);
  ASSERT_GT(want.x, 0);
  for (Bd16Direction mode : {Bd16Direction::U, Bd16Direction::V, Bd16Direction::Random}) {
    Bd16LineSampler sampler(light, material, p.x, p.n, p.wo, mode);
    Statistics stats = sample_mean(20000, 7 + static_cast<int>(mode), [&](double u, Vec2 d) {
      return sampler.estimate_unoccluded(u, d);
    });
    EXPECT_LT(std::abs(stats.mean.x - want.x), 4.0 * stats.standard_error + 1e-9 * want.x)
        << "mode " << static_cast<int>(mode);
    EXPECT_NEAR(stats.mean.z / stats.mean.x, want.z / want.x, 1e-9);
    // Fixed directions with stratified offsets converge fast: 1024 strata, well within 0.1%.
    if (mode != Bd16Direction::Random) {
      Rgb sum{0, 0, 0};
      for (int i = 0; i < 1024; ++i) sum += sampler.estimate_unoccluded((i + 0.5) / 1024, {});
      EXPECT_NEAR(sum.x / 1024, want.x, 1e-3 * want.x) << "mode " << static_cast<int>(mode);
    }
  }
}

TEST(Bd16Estimator, UnbiasedForAnUnoccludedQuad) {
  Light quad = make_quad_light({-0.5, -0.3, 2}, {1.2, 0, 0}, {0.3, -0.8, 0}, {3, 3, 3});
  ASSERT_LT(quad.normal.z, 0);
  check_unbiased_lambert(quad, {{0.2, 0.1, 0}, {0, 0, 1}, normalize(Vec3{0.1, 0.3, 1})});
  // Tilted receiver whose horizon cuts the light.
  check_unbiased_lambert(quad,
                         {{0.1, 0, 1.5}, normalize(Vec3{1, 0, 0.2}), normalize(Vec3{1, 0, 1})});
}

TEST(Bd16Estimator, UnbiasedForAnUnoccludedTriangle) {
  Light triangle = make_polygon_light({{-1, 0, 2}, {0.2, 1.1, 2}, {1, -0.4, 2}}, {2, 1, 0.5});
  if (triangle.normal.z > 0) {
    triangle = make_polygon_light({{-1, 0, 2}, {1, -0.4, 2}, {0.2, 1.1, 2}}, {2, 1, 0.5});
  }
  check_unbiased_lambert(triangle, {{0.3, 0.2, 0}, {0, 0, 1}, {0, 0, 1}});
  check_unbiased_lambert(
      triangle, {{0.5, 0.4, 1.7}, normalize(Vec3{-1, 0.3, 0.1}), normalize(Vec3{-1, 0, 0.5})});
}

// Brute-force visibility: a ray from x to p blocked by any triangle strictly between.
bool blocked(const std::vector<Vec3>& positions, const std::vector<uint32_t>& indices,
             const Vec3& x, const Vec3& p) {
  Vec3 d = p - x;
  for (size_t i = 0; i < indices.size(); i += 3) {
    Vec3 v0 = positions[indices[i]], v1 = positions[indices[i + 1]], v2 = positions[indices[i + 2]];
    Vec3 e1 = v1 - v0, e2 = v2 - v0;
    Vec3 pv = cross(d, e2);
    double det = dot(e1, pv);
    if (std::abs(det) < 1e-14) continue;
    Vec3 tv = x - v0;
    double u = dot(tv, pv) / det;
    if (u < 0 || u > 1) continue;
    Vec3 qv = cross(tv, e1);
    double v = dot(d, qv) / det;
    if (v < 0 || u + v > 1) continue;
    double t = dot(e2, qv) / det;
    if (t > 1e-9 && t < 1 - 1e-9) return true;
  }
  return false;
}

// f of the two materials, written here from SCENE_FORMAT.md's definitions.
Rgb brdf(const Material& m, const Vec3& n, const Vec3& wo, const Vec3& wi) {
  if (m.type == MaterialType::Lambert) return m.albedo / kPi;
  Vec3 mirror = 2.0 * dot(wo, n) * n - wo;
  double c = dot(mirror, wi);
  double lobe = c > 0 ? (m.exponent + 2) / (2 * kPi) * std::pow(c, m.exponent) : 0.0;
  return m.kd / kPi + m.ks * lobe;
}

TEST(Bd16Estimator, OccludedAgainstAreaSampledReference) {
  Light quad = make_quad_light({-0.5, -0.5, 2}, {1, 0, 0}, {0, -1, 0}, {2, 2, 2});
  // Occluders: a triangle and a tilted quad (two triangles) between the plane z = 0 and the light.
  std::vector<Vec3> positions{{-0.6, -0.4, 1.0}, {0.3, -0.2, 1.1}, {-0.2, 0.5, 0.9},
                              {0.1, 0.2, 1.4},   {0.7, 0.1, 1.5},  {0.6, 0.8, 1.3},
                              {0.0, 0.9, 1.2}};
  std::vector<uint32_t> indices{0, 1, 2, 3, 4, 5, 3, 5, 6};
  LineQuery query(positions, indices);
  ShadingPoint p{{0.05, 0.1, 0}, {0, 0, 1}, normalize(Vec3{-0.2, -0.3, 1})};
  for (const Material& material : {lambert_material(), phong_material(30)}) {
    // Reference: 600 x 600 cell midpoints on the light, brute-force visibility.
    constexpr int kGrid = 600;
    Rgb reference{0, 0, 0};
    for (int i = 0; i < kGrid; ++i) {
      for (int j = 0; j < kGrid; ++j) {
        Vec3 y = quad.origin + ((i + 0.5) / kGrid) * quad.edge1 + ((j + 0.5) / kGrid) * quad.edge2;
        if (blocked(positions, indices, p.x, y)) continue;
        Vec3 d = y - p.x;
        double r2 = dot(d, d);
        Vec3 wi = d / std::sqrt(r2);
        double g = std::max(0.0, dot(p.n, wi)) * std::max(0.0, -dot(quad.normal, wi)) / r2;
        reference += brdf(material, p.n, p.wo, wi) * g;
      }
    }
    reference = reference * quad.radiance * (quad.area / (kGrid * kGrid));
    for (Bd16Direction mode : {Bd16Direction::U, Bd16Direction::V, Bd16Direction::Random}) {
      Bd16LineSampler sampler(quad, material, p.x, p.n, p.wo, mode);
      Rgb sum{0, 0, 0};
      constexpr int kLines = 4096;
      for (int i = 0; i < kLines; ++i)
        sum += sampler.estimate((i + 0.5) / kLines, {0.27, 0}, query);
      Rgb estimate = sum / kLines;
      EXPECT_NEAR(estimate.x, reference.x, 3e-3 * reference.x)
          << material.name << " mode " << static_cast<int>(mode);
      // The occluders matter here: the unoccluded value is clearly larger.
      Rgb unoccluded{0, 0, 0};
      for (int i = 0; i < 256; ++i)
        unoccluded += sampler.estimate_unoccluded((i + 0.5) / 256, {0.27, 0});
      EXPECT_GT(unoccluded.x / 256, 1.1 * estimate.x);
    }
  }
}

TEST(Bd16Estimator, StratifiedOffsetsReduceVarianceStrongly) {
  Light quad = make_quad_light({-0.5, -0.5, 2}, {1, 0, 0}, {0, -1, 0}, {2, 2, 2});
  std::vector<Vec3> positions{{-0.6, -0.4, 1.0}, {0.3, -0.2, 1.1}, {-0.2, 0.5, 0.9}};
  std::vector<uint32_t> indices{0, 1, 2};
  LineQuery query(positions, indices);
  ShadingPoint p{{0.05, 0.1, 0}, {0, 0, 1}, {0, 0, 1}};
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  constexpr int kSamples = 32, kTrials = 400;
  // One direction per shading point, fixed across trials (u, v, and one rand direction), so the
  // variance is that of the offsets alone.
  for (Bd16Direction mode : {Bd16Direction::U, Bd16Direction::V, Bd16Direction::Random}) {
    Bd16LineSampler sampler(quad, lambert_material(), p.x, p.n, p.wo, mode);
    Vec2 direction_u{0.3, 0};
    auto variance = [&](bool stratified) {
      double sum = 0, sum_squares = 0;
      for (int trial = 0; trial < kTrials; ++trial) {
        double value = 0;
        for (int i = 0; i < kSamples; ++i) {
          // Jittered strata (what generate_1d's stratified pattern produces) or independent.
          double u = stratified ? (i + uniform(rng)) / kSamples : uniform(rng);
          value += sampler.estimate(u, direction_u, query).x;
        }
        value /= kSamples;
        sum += value;
        sum_squares += value * value;
      }
      double mean = sum / kTrials;
      return sum_squares / kTrials - mean * mean;
    };
    double random_variance = variance(false), stratified_variance = variance(true);
    std::printf("mode %d, %d offsets: variance random %.3e, stratified %.3e (ratio %.1f)\n",
                static_cast<int>(mode), kSamples, random_variance, stratified_variance,
                random_variance / stratified_variance);
    EXPECT_LT(stratified_variance, random_variance / 10.0)
        << "mode " << static_cast<int>(mode) << " random " << random_variance << " stratified "
        << stratified_variance;
  }
}

TEST(Bd16Estimator, RefusesUnsupportedLightsAndMaterials) {
  Light quad = make_quad_light({0, 0, 1}, {1, 0, 0}, {0, 1, 0}, {1, 1, 1});
  EXPECT_FALSE(Bd16LineSampler::unsupported(quad, lambert_material()).has_value());
  EXPECT_FALSE(Bd16LineSampler::unsupported(quad, phong_material(100)).has_value());
  Material ggx;
  ggx.name = "brushed";
  ggx.type = MaterialType::Ggx;
  auto why = Bd16LineSampler::unsupported(quad, ggx);
  ASSERT_TRUE(why.has_value());
  EXPECT_NE(why->find("line-bd16"), std::string::npos);
  EXPECT_NE(why->find("brushed"), std::string::npos);
  EXPECT_NE(why->find("ggx"), std::string::npos);
  Light gaussian = quad;
  gaussian.profile = ProfileType::Gaussian;
  why = Bd16LineSampler::unsupported(gaussian, lambert_material());
  ASSERT_TRUE(why.has_value());
  EXPECT_NE(why->find("gaussian"), std::string::npos);
  Light disk = make_disk_light({0, 0, 1}, {0, 0, -1}, 0.5, {1, 1, 1});
  why = Bd16LineSampler::unsupported(disk, lambert_material());
  ASSERT_TRUE(why.has_value());
  EXPECT_NE(why->find("disk"), std::string::npos);
}

TEST(Bd16Estimator, DegenerateConfigurationsAreFinite) {
  std::vector<Vec3> positions{{-0.1, -0.1, 0.5}, {0.1, -0.1, 0.5}, {0, 0.1, 0.5}};
  std::vector<uint32_t> indices{0, 1, 2};
  LineQuery query(positions, indices);
  struct Case {
    Light light;
    ShadingPoint p;
    bool zero;
  };
  Light quad = make_quad_light({-0.5, -0.5, 1}, {1, 0, 0}, {0, -1, 0}, {1, 1, 1});
  std::vector<Case> cases{
      {quad, {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}}, true},               // x on the light's plane
      {quad, {{0, 0, 2}, {0, 0, 1}, {0, 0, 1}}, true},               // behind the light
      {quad, {{0, 0, 0.5}, {0, 0, -1}, {0, 0, -1}}, true},           // light below the horizon
      {quad, {{0.5, 0.5, 1 - 1e-12}, {0, 0, 1}, {0, 0, 1}}, false},  // at a corner, just below
      {quad, {{0.2, 0, 0}, {1, 0, 0}, {1, 0, 0}}, false},  // normal parallel to the light's edges
      {make_quad_light({0, 0, 40}, {0.01, 0, 0}, {0, -0.01, 0}, {1, 1, 1}),
       {{0, 0, 0}, {0, 0, 1}, {0, 0, 1}},
       false},  // 1 cm light at 40 m
      {make_quad_light({0, 0, 0.01}, {0.001, 0, 0}, {0, -0.001, 0}, {1, 1, 1}),
       {{0, 0, 0}, {0, 0, 1}, {0, 0, 1}},
       false},  // 1 mm light
  };
  for (size_t c = 0; c < cases.size(); ++c) {
    for (const Material& material : {lambert_material(), phong_material(10000)}) {
      for (Bd16Direction mode : {Bd16Direction::U, Bd16Direction::V, Bd16Direction::Random}) {
        Bd16LineSampler sampler(cases[c].light, material, cases[c].p.x, cases[c].p.n, cases[c].p.wo,
                                mode);
        for (double u : {0.0, 1e-300, 0.25, 0.5, 1.0 - 1e-16, 1.0}) {
          for (double d : {0.0, 0.5, 1.0}) {
            Rgb v = sampler.estimate(u, {d, 0}, query);
            EXPECT_TRUE(is_finite(v)) << "case " << c;
            EXPECT_GE(v.x, 0.0) << "case " << c;
            if (cases[c].zero) {
              EXPECT_EQ(v.x, 0.0) << "case " << c;
            }
          }
        }
      }
    }
  }
  // Non-finite shading point: zero.
  double nan = std::numeric_limits<double>::quiet_NaN();
  Bd16LineSampler sampler(quad, lambert_material(), {nan, 0, 0}, {0, 0, 1}, {0, 0, 1},
                          Bd16Direction::U);
  EXPECT_EQ(sampler.estimate(0.5, {0, 0}, query).x, 0.0);
}

}  // namespace
}  // namespace penumbra
