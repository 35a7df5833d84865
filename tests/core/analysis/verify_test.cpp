// The bias check of `penumbra verify` (core/analysis/bias_check.h, verify.h).
//
// Synthetic films of known mean and variance: an unbiased set flags at the normal rate of its
// threshold and a planted bias is found in its block only. Rendered: a small area-sampling
// estimator written here (the renderer's camera, hits and shadow rays, uniform points on the
// light) with a deliberately wrong pdf is caught against the exact reference, and the same
// estimator with the right pdf passes, as does the shipped `area` at the same budget.
#include "core/analysis/verify.h"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>

#include "core/lights/light_geometry.h"
#include "core/render/camera.h"
#include "core/render/pixel_filter.h"
#include "core/render/shading.h"
#include "core/render/tile.h"

namespace penumbra {
namespace {

// A film of `width` x `height` whose every pixel is normal with mean `mean` and the variance of
// the mean `variance` (the variance layer states it exactly).
Film synthetic_film(int width, int height, double mean, double variance, std::mt19937_64& random) {
  Film film;
  film.color = Image(width, height);
  film.variance = Image(width, height);
  std::normal_distribution<double> normal(mean, std::sqrt(variance));
  for (size_t i = 0; i < film.color.rgb.size(); ++i) {
    film.color.rgb[i] = float(normal(random));
    film.variance.rgb[i] = float(variance);
  }
  return film;
}

// At 3 sigma (two-sided rate 0.27%) over 200 checks of 4 runs, 64 blocks and 3 channels (38400
// tests): the measured rate is within 4 standard errors (0.11%) of the normal tail, since the
// runs' variance layers are exact; and the Bonferroni bound is T times the tail.
TEST(BiasCheck, UnbiasedRunsFlagAtTheNormalRate) {
  std::mt19937_64 random(7);
  BiasCheckOptions options;
  options.block_size = 4;
  options.sigma = 3;
  const double tail = normal_two_sided_tail(3);
  EXPECT_NEAR(tail, 2.6997960632601866e-3, 1e-15);
  EXPECT_NEAR(normal_two_sided_tail(5), 5.733031437583878e-7, 1e-20);
  long flags = 0, tests = 0;
  for (int check = 0; check < 200; ++check) {
    Film reference = synthetic_film(32, 32, 0.5, 1e-4, random);
    std::vector<Film> runs;
    for (int r = 0; r < 4; ++r) runs.push_back(synthetic_film(32, 32, 0.5, 4e-4, random));
    BiasCheckResult result = check_bias(reference, nullptr, runs, options);
    ASSERT_EQ(result.blocks, 64);
    ASSERT_EQ(result.tests, 192);
    EXPECT_NEAR(result.family_false_alarm_bound, std::min(1.0, 192 * tail), 1e-12);
    flags += long(result.flagged.size());
    tests += result.tests;
  }
  const double rate = double(flags) / tests;
  EXPECT_NEAR(rate, tail, 4 * std::sqrt(tail / tests)) << flags << " of " << tests;
}

// A bias of 10 standard errors in one block of one channel: flagged there, and nowhere else at
// 5 sigma. The standard error of a 4x4 block of 4 runs with per-pixel variance v (runs) and w
// (reference) is sqrt(v / (16 * 4) + w / 16).
TEST(BiasCheck, FindsAPlantedBiasInItsBlock) {
  std::mt19937_64 random(11);
  const double v = 4e-4, w = 1e-4;
  const double se = std::sqrt(v / 64 + w / 16);
  Film reference = synthetic_film(32, 32, 0.5, w, random);
  std::vector<Film> runs;
  for (int r = 0; r < 4; ++r) {
    runs.push_back(synthetic_film(32, 32, 0.5, v, random));
    for (int y = 8; y < 12; ++y)
      for (int x = 20; x < 24; ++x) runs.back().color.rgb[(size_t(y) * 32 + x) * 3 + 1] += 10 * se;
  }
  BiasCheckOptions options;
  options.block_size = 4;
  BiasCheckResult result = check_bias(reference, nullptr, runs, options);
  ASSERT_EQ(result.flagged.size(), 1u);
  const BlockTest& flagged = result.flagged[0];
  EXPECT_EQ(flagged.x0, 20);
  EXPECT_EQ(flagged.y0, 8);
  EXPECT_EQ(flagged.channel, 1);
  EXPECT_NEAR(flagged.z, 10, 1.5);  // the standard error itself is estimated
  EXPECT_FALSE(result.passed());
  EXPECT_NE(bias_check_text(result, "planted").find("FAIL: 1 block-channel tests beyond 5 sigma"),
            std::string::npos);
}

TEST(BiasCheck, RefusesBadInput) {
  std::mt19937_64 random(1);
  Film reference = synthetic_film(8, 8, 1, 1e-3, random);
  std::vector<Film> one{synthetic_film(8, 8, 1, 1e-3, random)};
  EXPECT_THROW(check_bias(reference, nullptr, one), std::invalid_argument);
  std::vector<Film> sizes{synthetic_film(8, 8, 1, 1e-3, random),
                          synthetic_film(8, 4, 1, 1e-3, random)};
  try {
    check_bias(reference, nullptr, sizes);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "run 1 is 8x4, the reference 8x8");
  }
}

std::shared_ptr<const Scene> small_scene(const std::string& name, int width) {
  const std::string path = std::string(PENUMBRA_SOURCE_DIR) + "/scenes/" + name + ".json";
  return std::make_shared<const Scene>(scene_at_width(load_scene(path), width));
}

// Uniform area sampling of every light, one sample per light and camera sample, with the pdf
// it claims scaled by `pdf_scale` and its first coordinate warped by sqrt when `warp` (a
// density 2u that the pdf ignores): the kinds of mismatch that slip into renderers.
RunRenderer area_sampling_runs(std::shared_ptr<const Scene> scene, uint32_t spp, double pdf_scale,
                               bool warp) {
  auto shading = std::make_shared<SceneShading>(scene, parse_method("area"));
  return [scene, shading, spp, pdf_scale, warp](int, uint64_t seed) {
    const int width = scene->camera.width, height = scene->camera.height;
    const CameraRays camera(scene->camera);
    const PixelFilterSampler filter(scene->camera.filter);
    TileAccumulator sums(TileRect{0, 0, width, height});
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x)
        for (uint32_t pass = 0; pass < spp; ++pass) {
          const uint64_t pixel = uint64_t(y) * width + x;
          StreamKey key{seed, pixel, pass, 0};
          const Vec2 offset = filter.position(random_uniform(key, 0, 0), random_uniform(key, 0, 1));
          const auto hit =
              shading->first_hit(camera.origin(), camera.direction(x + offset.x, y + offset.y));
          Rgb radiance = hit.emitted;
          if (hit.shading_point) {
            const ShadingPoint& sp = *hit.shading_point;
            for (size_t l = 0; l < scene->lights.size(); ++l) {
              const Light& light = scene->lights[l];
              if (!light_faces_point(light, sp.position)) continue;
              key.stream = 1 + uint32_t(l);
              Vec2 u{random_uniform(key, 0, 0), random_uniform(key, 0, 1)};
              if (warp) u.x = std::sqrt(u.x);
              const Vec3 point = light_point_uniform(light, u);
              const double area = length(cross(light.edge1, light.edge2));
              const double pdf = pdf_scale / area;
              const Vec3 d = point - sp.position;
              const double r2 = length_squared(d);
              const Vec3 wi = d / std::sqrt(r2);
              const double cos_x = dot(sp.normal, wi), cos_l = -dot(light.normal, wi);
              if (cos_x <= 0 || cos_l <= 0) continue;
              if (shading->occluded(sp.position, sp.normal, point)) continue;
              radiance += shading_bsdf(sp, wi) * emitted_radiance(light, point, -wi) *
                          (cos_x * cos_l / r2 / pdf);
            }
          }
          sums.add_sample(int64_t(pixel), radiance);
        }
    return assemble_film(width, height, std::span<const TileAccumulator>(&sums, 1));
  };
}

class WrongPdf : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    scene_ = small_scene("quad-over-floor", 32);
    ExactReferenceOptions options;
    options.camera_samples = 32;
    options.threads = 1;
    reference_ = std::make_unique<VerifyReference>(render_verify_reference(scene_, options));
  }
  static void TearDownTestSuite() {
    reference_.reset();
    scene_.reset();
  }
  static std::shared_ptr<const Scene> scene_;
  static std::unique_ptr<VerifyReference> reference_;
};
std::shared_ptr<const Scene> WrongPdf::scene_;
std::unique_ptr<VerifyReference> WrongPdf::reference_;

// The right pdf passes: the test has no false alarm at this budget (the measured worst |z| is
// printed). It agrees with the shipped `area` too.
TEST_F(WrongPdf, TheRightPdfPasses) {
  EXPECT_DOUBLE_EQ(reference_->exact_share, 1.0);
  VerifyResult mine = verify_runs(*reference_, 4, 1, area_sampling_runs(scene_, 16, 1.0, false));
  EXPECT_TRUE(mine.check.passed()) << bias_check_text(mine.check, "area (test copy)");
  EXPECT_LT(std::abs(mine.check.worst.z), 5);
  RenderBudget budget;
  budget.spp = 16;
  VerifyResult shipped = verify_runs(
      *reference_, 4, 1, method_run_renderer(scene_, "area", Pattern::Random, budget, 1));
  EXPECT_TRUE(shipped.check.passed()) << bias_check_text(shipped.check, "area");
  EXPECT_EQ(shipped.spp, (std::vector<uint32_t>{16, 16, 16, 16}));
}

// A pdf 3% too large (a forgotten factor) darkens every lit block by 3%, about 5 standard errors
// of a typical block at this budget: caught, every flagged block below the reference.
TEST_F(WrongPdf, APdfThreePercentTooLargeIsCaught) {
  VerifyResult result = verify_runs(*reference_, 4, 1, area_sampling_runs(scene_, 16, 1.03, false));
  ASSERT_FALSE(result.check.passed());
  EXPECT_GE(result.check.flagged.size(), 10u) << bias_check_text(result.check, "pdf x 1.03");
  for (const BlockTest& t : result.check.flagged) {
    EXPECT_LT(t.z, 0);
    EXPECT_NEAR(t.estimate / t.reference, 1 / 1.03, 0.02);
  }
}

// Points drawn with density 2u along the light's first edge but weighted as if uniform: too
// bright where the light's far side matters, too dark elsewhere.
TEST_F(WrongPdf, AWarpTheDensityIgnoresIsCaught) {
  VerifyResult result = verify_runs(*reference_, 4, 1, area_sampling_runs(scene_, 16, 1.0, true));
  ASSERT_FALSE(result.check.passed()) << bias_check_text(result.check, "warped");
  EXPECT_GT(std::abs(result.check.worst.z), 8);
}

TEST_F(WrongPdf, RefusesRunsThatShareTheReferenceSeed) {
  EXPECT_THROW(
      verify_runs(*reference_, 4, reference_->seed - 1, area_sampling_runs(scene_, 1, 1.0, false)),
      std::invalid_argument);
}

}  // namespace
}  // namespace penumbra
