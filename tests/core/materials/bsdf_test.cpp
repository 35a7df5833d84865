// BSDFs: sampling against the density (chi-square over directions), the density the sampler
// reports, energy bounds, reciprocity, closed-form values and robustness.

#include "core/materials/bsdf.h"

#include <gtest/gtest.h>

#include <vector>

#include "core/materials/ggx.h"
#include "tests/core/materials/direction_binning.h"
#include "tests/core/strategies/test_support.h"

namespace penumbra {
namespace {

using test::Rng;

Vec3 direction_at_angle(const Vec3& n, double degrees, double azimuth = 0.7) {
  Frame f = Frame::from_normal(n);
  double t = degrees * kPi / 180.0;
  return f.to_world(
      {std::sin(t) * std::cos(azimuth), std::sin(t) * std::sin(azimuth), std::cos(t)});
}

Vec3 mirror(const Vec3& wo, const Vec3& n) {
  return 2.0 * dot(wo, n) * n - wo;
}

struct SamplingCase {
  std::string name;
  Material material;
  double wo_degrees;
  bool around_mirror;  // bin around the mirror direction (else around the normal)
  bool log_scale;
};

void PrintTo(const SamplingCase& c, std::ostream* os) {
  *os << c.name;
}

std::vector<SamplingCase> sampling_cases() {
  using test::ggx;
  using test::lambert;
  using test::phong;
  return {
      {"lambert", lambert({0.7, 0.5, 0.3}), 30, false, false},
      {"phong_n1", phong({0.5, 0.5, 0.5}, {0.3, 0.3, 0.3}, 1), 45, false, false},
      {"phong_n50", phong({0.2, 0.2, 0.2}, {0.7, 0.7, 0.7}, 50), 30, true, true},
      {"phong_n10000_specular", phong({0, 0, 0}, {1, 1, 1}, 1e4), 60, true, true},
      {"phong_n10000_mixed", phong({0.3, 0.3, 0.3}, {0.6, 0.6, 0.6}, 1e4), 20, true, true},
      {"ggx_r005", ggx({0.2, 0.2, 0.2}, {0.8, 0.8, 0.8}, 0.05), 40, true, true},
      {"ggx_r05", ggx({0.1, 0.1, 0.1}, {0.9, 0.9, 0.9}, 0.5), 60, true, false},
      {"ggx_r1", ggx({0, 0, 0}, {0.9, 0.9, 0.9}, 1.0), 75, true, false},
      {"ggx_r005_grazing", ggx({0.1, 0.1, 0.1}, {0.9, 0.9, 0.9}, 0.05), 85, true, true},
      {"ggx_r05_mixed", ggx({0.5, 0.4, 0.3}, {0.04, 0.04, 0.04}, 0.5), 10, false, false},
  };
}

class BsdfSampling : public ::testing::TestWithParam<SamplingCase> {};

TEST_P(BsdfSampling, SamplesFollowTheReportedDensity) {
  const SamplingCase& c = GetParam();
  Vec3 n = normalize(Vec3{0.2, 0.3, 1.0});
  Vec3 wo = direction_at_angle(n, c.wo_degrees);
  test::DirectionBinning binning;
  binning.frame = Frame::from_normal(c.around_mirror ? normalize(mirror(wo, n)) : n);
  binning.log_scale = c.log_scale;
  const int samples = 400000;
  std::vector<double> observed(binning.y_bins * binning.phi_bins + 1, 0.0);
  Rng rng(1234);
  double worst_pdf_mismatch = 0;
  for (int i = 0; i < samples; ++i) {
    auto s = sample_bsdf(c.material, n, wo, rng.uniform2());
    if (!s) {
      observed.back() += 1;
      continue;
    }
    ASSERT_NEAR(length(s->wi), 1.0, 1e-12);
    ASSERT_GT(dot(s->wi, n), 0.0);
    worst_pdf_mismatch =
        std::max(worst_pdf_mismatch,
                 test::relative_difference(s->pdf_solid_angle, pdf_bsdf(c.material, n, wo, s->wi)));
    observed[binning.bin(s->wi)] += 1;
  }
  EXPECT_LE(worst_pdf_mismatch, 1e-9) << "sample's pdf differs from pdf_bsdf";
  std::vector<double> expected =
      binning.integrate([&](const Vec3& wi) { return pdf_bsdf(c.material, n, wo, wi); });
  double total = 0;
  for (double& e : expected) {
    e *= samples;
    total += e;
  }
  EXPECT_LE(total, samples * (1 + 2e-3)) << "density integrates to more than one";
  expected.push_back(std::max(0.0, samples - total));  // failed samples (below the horizon)
  auto result = test::chi_square_test(observed, expected);
  EXPECT_TRUE(result.passed) << c.name << ": " << result.summary();
}

INSTANTIATE_TEST_SUITE_P(Materials, BsdfSampling, ::testing::ValuesIn(sampling_cases()),
                         [](const auto& info) { return info.param.name; });

// Integral of f cos over the hemisphere, estimated with the BSDF's own sampling.
struct Estimate {
  double mean = 0, standard_error = 0;
};
Estimate directional_albedo(const Material& m, const Vec3& n, const Vec3& wo, int samples,
                            uint64_t seed) {
  Rng rng(seed);
  double sum = 0, sum_sq = 0;
  for (int i = 0; i < samples; ++i) {
    double value = 0;
    if (auto s = sample_bsdf(m, n, wo, rng.uniform2())) {
      Rgb f = eval_bsdf(m, n, wo, s->wi);
      value = luminance(f) * dot(n, s->wi) / s->pdf_solid_angle;
    }
    EXPECT_TRUE(std::isfinite(value));
    sum += value;
    sum_sq += value * value;
  }
  Estimate e;
  e.mean = sum / samples;
  double variance = std::max(0.0, sum_sq / samples - e.mean * e.mean);
  e.standard_error = std::sqrt(variance / (samples - 1));
  return e;
}

TEST(BsdfEnergy, LambertWithAlbedoOneReflectsEverything) {
  Vec3 n{0, 0, 1};
  for (double angle : {0.0, 30.0, 60.0, 89.0}) {
    Estimate e =
        directional_albedo(test::lambert({1, 1, 1}), n, direction_at_angle(n, angle), 100000, 7);
    EXPECT_NEAR(e.mean, 1.0, 1e-9) << angle;  // f cos / pdf is exactly 1 per sample
  }
}

TEST(BsdfEnergy, PhongLobeIsNormalizedAtNormalIncidenceAndBoundedElsewhere) {
  Vec3 n{0, 0, 1};
  for (double exponent : {1.0, 50.0, 1e4}) {
    Material m = test::phong({0, 0, 0}, {1, 1, 1}, exponent);
    // wo = n: the lobe is centred on the normal and (n+2)/(2 pi) cos^(n+1) integrates to 1.
    Estimate normal = directional_albedo(m, n, n, 200000, 11);
    EXPECT_NEAR(normal.mean, 1.0, 4 * normal.standard_error + 1e-9) << exponent;
    for (double angle : {30.0, 60.0, 85.0}) {
      Estimate e = directional_albedo(m, n, direction_at_angle(n, angle), 200000, 13);
      EXPECT_LE(e.mean, 1.0 + 4 * e.standard_error) << exponent << " " << angle;
    }
  }
  Estimate mixed = directional_albedo(test::phong({0.5, 0.5, 0.5}, {0.5, 0.5, 0.5}, 20), n,
                                      direction_at_angle(n, 40), 200000, 17);
  EXPECT_LE(mixed.mean, 1.0 + 4 * mixed.standard_error);
}

TEST(BsdfEnergy, GgxLobeWithF0OneLosesOnlyWhatSingleScatteringLoses) {
  Vec3 n{0, 0, 1};
  for (double roughness : {0.05, 0.5, 1.0}) {
    Material m = test::ggx({0, 0, 0}, {1, 1, 1}, roughness);
    for (double angle : {0.0, 45.0, 80.0}) {
      Estimate e = directional_albedo(m, n, direction_at_angle(n, angle), 200000, 19);
      EXPECT_LE(e.mean, 1.0 + 4 * e.standard_error) << roughness << " " << angle;
      if (roughness == 0.05 && angle < 50) {
        EXPECT_GE(e.mean, 0.97) << angle;
      }
    }
  }
}

std::vector<Material> all_materials() {
  return {test::lambert({0.7, 0.5, 0.3}),
          test::phong({0.3, 0.2, 0.1}, {0.5, 0.6, 0.7}, 1),
          test::phong({0.3, 0.2, 0.1}, {0.5, 0.6, 0.7}, 50),
          test::phong({0.0, 0.0, 0.0}, {1, 1, 1}, 1e4),
          test::ggx({0.2, 0.1, 0.05}, {0.9, 0.6, 0.3}, 1e-4),
          test::ggx({0.2, 0.1, 0.05}, {0.9, 0.6, 0.3}, 0.05),
          test::ggx({0.2, 0.1, 0.05}, {0.9, 0.6, 0.3}, 0.5),
          test::ggx({0.2, 0.1, 0.05}, {0.9, 0.6, 0.3}, 1.0)};
}

TEST(BsdfReciprocity, SwappingDirectionsGivesTheSameValue) {
  Rng rng(99);
  Vec3 n = normalize(Vec3{-0.3, 0.1, 1});
  Frame frame = Frame::from_normal(n);
  for (const Material& m : all_materials()) {
    for (int i = 0; i < 2000; ++i) {
      Vec3 a = rng.unit_vector(), b = rng.unit_vector();
      Vec3 wo = frame.to_world({a.x, a.y, std::abs(a.z)});
      Vec3 wi = frame.to_world({b.x, b.y, std::abs(b.z)});
      Rgb f1 = eval_bsdf(m, n, wo, wi), f2 = eval_bsdf(m, n, wi, wo);
      for (int k = 0; k < 3; ++k)
        ASSERT_LE(test::relative_difference(f1[k], f2[k]), 1e-10) << m.name << " " << i;
    }
  }
}

TEST(BsdfValues, MatchTheirDefinitions) {
  Vec3 n{0, 0, 1};
  Vec3 wo = direction_at_angle(n, 35);
  Vec3 wi = direction_at_angle(n, 50, 2.0);
  // lambert: albedo / pi.
  Rgb lambert = eval_bsdf(test::lambert({0.7, 0.5, 0.3}), n, wo, wi);
  EXPECT_NEAR(lambert.y, 0.5 / kPi, 1e-15);
  // phong in the mirror direction: kd/pi + ks (n+2)/(2 pi).
  Material p = test::phong({0.2, 0.2, 0.2}, {0.5, 0.5, 0.5}, 30);
  EXPECT_NEAR(eval_bsdf(p, n, wo, mirror(wo, n)).x, 0.2 / kPi + 0.5 * 32 / (2 * kPi), 1e-12);
  // phong elsewhere: the textbook formula with the angle to R.
  double cos_alpha = dot(mirror(wo, n), wi);
  EXPECT_NEAR(eval_bsdf(p, n, wo, wi).x,
              0.2 / kPi + 0.5 * 32 / (2 * kPi) * std::pow(std::max(0.0, cos_alpha), 30), 1e-12);
  // ggx: the textbook forms (cos-based D, tan-based Lambda) at a benign configuration.
  double alpha = 0.3;
  Material g = test::ggx({0.1, 0.1, 0.1}, {0.6, 0.6, 0.6}, alpha);
  Vec3 h = normalize(wo + wi);
  double cos_h = h.z;
  double denom = cos_h * cos_h * (alpha * alpha - 1) + 1;
  double d = alpha * alpha / (kPi * denom * denom);
  auto lambda = [&](double c) {
    double tan_sq = (1 - c * c) / (c * c);
    return (-1 + std::sqrt(1 + alpha * alpha * tan_sq)) / 2;
  };
  double g2 = 1 / (1 + lambda(wo.z) + lambda(wi.z));
  double fresnel = 0.6 + 0.4 * std::pow(1 - dot(wi, h), 5);
  double expected = 0.1 / kPi + d * g2 * fresnel / (4 * wo.z * wi.z);
  EXPECT_NEAR(eval_bsdf(g, n, wo, wi).x, expected, 1e-12 * expected);
  // Below the horizon: zero.
  EXPECT_TRUE(is_black(eval_bsdf(g, n, wo, direction_at_angle(n, 95))));
  EXPECT_EQ(pdf_bsdf(g, n, wo, direction_at_angle(n, 95)), 0.0);
}

TEST(BsdfRobustness, ExtremeParametersAndDirectionsStayFinite) {
  Rng rng(5);
  std::vector<Material> materials = all_materials();
  materials.push_back(test::ggx({0, 0, 0}, {1, 1, 1}, 0));  // clamped to alpha 1e-4
  materials.push_back(test::phong({0, 0, 0}, {1, 1, 1}, 1e6));
  std::vector<Vec3> normals = {{0, 0, 1}, {0, 0, -1}, normalize(Vec3{1, 1e-9, 0})};
  std::vector<double> angles = {0, 45, 89.9, 90 - 1e-7, 90 - 1e-12, 90};
  std::vector<Vec2> special_u = {{0, 0},
                                 {0, 1},
                                 {1, 0},
                                 {1, 1},
                                 {0x1.fffffffffffffp-1, 0.5},
                                 {0.5, 0x1.fffffffffffffp-1},
                                 {1e-300, 1e-300}};
  for (const Material& m : materials) {
    for (const Vec3& n : normals) {
      for (double angle : angles) {
        Vec3 wo = direction_at_angle(n, angle);
        std::vector<Vec2> us = special_u;
        for (int i = 0; i < 200; ++i) us.push_back(rng.uniform2());
        for (const Vec2& u : us) {
          auto s = sample_bsdf(m, n, wo, u);
          if (!s) continue;
          ASSERT_TRUE(is_finite(s->wi)) << m.name;
          ASSERT_TRUE(std::isfinite(s->pdf_solid_angle) && s->pdf_solid_angle > 0) << m.name;
          Rgb f = eval_bsdf(m, n, wo, s->wi);
          ASSERT_TRUE(is_finite(f)) << m.name << " angle " << angle;
          ASSERT_TRUE(std::isfinite(luminance(f) * dot(n, s->wi) / s->pdf_solid_angle));
          ASSERT_TRUE(std::isfinite(pdf_bsdf(m, n, wo, s->wi)));
        }
        for (int i = 0; i < 50; ++i) {
          Vec3 wi = rng.unit_vector();
          ASSERT_TRUE(is_finite(eval_bsdf(m, n, wo, wi))) << m.name;
          ASSERT_TRUE(std::isfinite(pdf_bsdf(m, n, wo, wi))) << m.name;
        }
      }
    }
  }
}

TEST(GgxVisibleNormals, DensityOfReflectedDirectionsIsNormalized) {
  // At normal incidence the visible normals follow D(h) cos(theta_h), whose CDF in tan^2 is
  // t / (alpha^2 + t); the reflection stays above the horizon for theta_h < 45 degrees, so the
  // density of reflected directions integrates to 1 / (1 + alpha^2). Quadrature over the sphere,
  // logarithmic around the normal for the narrow lobes.
  for (double alpha : {0.05, 0.5, 1.0}) {
    Vec3 wo{0, 0, 1};
    test::DirectionBinning binning;
    binning.frame = Frame::from_normal({0, 0, 1});
    // Linear for wide lobes: the horizon (y = 1/2) is then a bin edge.
    binning.log_scale = alpha < 0.2;
    double total = 0;
    for (double mass :
         binning.integrate([&](const Vec3& wi) { return ggx_reflection_pdf(wo, wi, alpha); }))
      total += mass;
    EXPECT_NEAR(total, 1.0 / (1.0 + alpha * alpha), 1e-4) << alpha;
  }
}

}  // namespace
}  // namespace penumbra
