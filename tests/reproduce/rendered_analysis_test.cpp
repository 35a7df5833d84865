// Units of the rendered-scene analysis behind `penumbra reproduce`:
//  - pattern_error.h: penumbra screening picks pixels whose visible fraction is in range and
//    refuses a region without penumbra; the measured squared error of an unbiased pattern equals
//    its variance around the reference (closed form: E[(e - r)^2] = Var e + (E e - r)^2 with E e
//    = r), checked against an independent estimate through the probe; the uniform pattern's error
//    is its bias and is the same with any trial count; results do not depend on the thread count.
//  - variance_convergence.h: unoccluded pixel, 2D stratified (jittered) area sampling of a smooth
//    integrand has variance ~ N^-2 and random sampling ~ N^-1 (closed forms of the slopes).
//  - disk_square_rejection.h: the paper's rejection sampling of a disk is unbiased: its mean
//    matches the closed form of an unoccluded disk seen on its axis, rho L R^2 / (h^2 + R^2).
//  - peters_reproduction.h: random configurations are convex, planar, face the shading point,
//    and the measurements are finite.

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <stdexcept>

#include "core/analysis/disk_square_rejection.h"
#include "core/analysis/pattern_error.h"
#include "core/analysis/peters_reproduction.h"
#include "core/analysis/variance_convergence.h"
#include "core/render/probe.h"
#include "core/scene/scene.h"

namespace penumbra {
namespace {

std::shared_ptr<const Scene> bundled(const std::string& name) {
  return std::make_shared<const Scene>(
      load_scene(std::string(PENUMBRA_SOURCE_DIR) + "/scenes/" + name + ".json"));
}

PatternErrorOptions small_options() {
  PatternErrorOptions o;
  o.samples = 16;
  o.trials = 64;
  o.region = "penumbra-large";
  o.pixel_stride = 6;
  o.max_pixels = 12;
  o.reference_samples = 4096;
  o.reference_trials = 2;
  o.threads = 2;
  return o;
}

TEST(PenumbraPixels, VisibleFractionsAreInRangeAndInsideTheRegion) {
  auto scene = bundled("spheres-plane-square");
  PatternErrorOptions o = small_options();
  PenumbraPixels found = find_penumbra_pixels(scene, o);
  ASSERT_GE(found.pixels.size(), 2u);
  EXPECT_LE(int(found.pixels.size()), o.max_pixels);
  EXPECT_GE(found.candidates, int(found.pixels.size()));
  const Region& region = scene->regions.at("penumbra-large");
  for (size_t i = 0; i < found.pixels.size(); ++i) {
    auto [x, y] = found.pixels[i];
    EXPECT_GE(x, region.x0);
    EXPECT_LT(x, region.x1);
    EXPECT_GE(y, region.y0);
    EXPECT_LT(y, region.y1);
    EXPECT_GE(found.visible_fraction[i], o.min_visible_fraction);
    EXPECT_LE(found.visible_fraction[i], o.max_visible_fraction);
  }
}

TEST(PenumbraPixels, RefusesUnknownRegionsAndRegionsWithoutPenumbra) {
  auto scene = bundled("spheres-plane-square");
  PatternErrorOptions o = small_options();
  o.region = "no-such-region";
  EXPECT_THROW(find_penumbra_pixels(scene, o), FormatError);
  // Fully lit points only (fraction 1 exactly is never "in the penumbra" below 0.9999).
  o.region.clear();
  o.min_visible_fraction = 0.99990;
  o.max_visible_fraction = 0.99995;
  o.pixel_stride = 64;
  EXPECT_THROW(find_penumbra_pixels(scene, o), std::invalid_argument);
  o = small_options();
  o.trials = 1;
  EXPECT_THROW(measure_pattern_errors(scene, {Pattern::Stratified}, o), std::invalid_argument);
}

TEST(PatternError, StratifiedErrorIsItsVarianceAroundTheReference) {
  auto scene = bundled("spheres-plane-square");
  PatternErrorOptions o = small_options();
  o.trials = 400;
  PatternErrorStudy study = measure_pattern_errors(scene, {Pattern::Stratified}, o);
  const PatternErrorResult& s = study.result(Pattern::Stratified);
  ASSERT_EQ(s.pixel_squared_error.size(), study.pixels.size());

  // The same variance measured independently by the probe (its own seeds).
  ProbeSpec probe;
  probe.pixels = study.pixels;
  const int counts[] = {16};
  ProbeResult probed = run_probe(scene, probe, "area", Pattern::Stratified, counts, 400, 99);
  double probe_variance = 0;
  for (const auto& runs : probed.points)
    probe_variance += (runs[0].variance.x + runs[0].variance.y + runs[0].variance.z) / 3.0;
  probe_variance /= double(probed.points.size());
  // 12 pixels x 400 trials: the two estimates of the mean squared error each have a relative
  // standard error of a few percent; 15% is > 3 of them.
  EXPECT_NEAR(s.mean_squared_error / probe_variance, 1.0, 0.15)
      << "study " << s.mean_squared_error << ", probe " << probe_variance;
  EXPECT_GT(s.relative_rms_error, 0);
  EXPECT_TRUE(std::isfinite(s.relative_rms_error));
  EXPECT_THROW(study.result(Pattern::Halton), std::out_of_range);
}

TEST(PatternError, UniformErrorIsDeterministicBiasAndThreadsDoNotMatter) {
  auto scene = bundled("spheres-plane-disk");
  PatternErrorOptions o = small_options();
  o.threads = 1;
  PatternErrorStudy one = measure_pattern_errors(scene, {Pattern::Uniform, Pattern::Stratified}, o);
  o.threads = 2;
  o.trials = 8;
  PatternErrorStudy other = measure_pattern_errors(scene, {Pattern::Uniform}, o);
  ASSERT_EQ(one.pixels, other.pixels);
  // The uniform pattern has no randomness: the same error whatever the trials and threads.
  EXPECT_EQ(one.result(Pattern::Uniform).pixel_squared_error,
            other.result(Pattern::Uniform).pixel_squared_error);
  o.trials = 64;
  o.threads = 2;
  PatternErrorStudy again =
      measure_pattern_errors(scene, {Pattern::Uniform, Pattern::Stratified}, o);
  EXPECT_EQ(one.result(Pattern::Stratified).pixel_squared_error,
            again.result(Pattern::Stratified).pixel_squared_error);
  EXPECT_EQ(one.reference, again.reference);
}

TEST(VarianceConvergence, UnoccludedSlopesMatchTheClosedForms) {
  auto scene = bundled("spheres-plane-square");
  // Fully lit ground points, far from the spheres' shadows.
  PatternErrorOptions o;
  o.min_visible_fraction = 0.9999;
  o.max_visible_fraction = 1.0;
  o.pixel_stride = 32;
  o.max_pixels = 3;
  o.threads = 2;
  PenumbraPixels lit = find_penumbra_pixels(scene, o);
  std::vector<int> counts = {4, 16, 64, 256};
  // Jittered sampling of a smooth 2D integrand: variance ~ N^(-1 - 2/d) = N^-2.
  VarianceConvergence stratified =
      measure_variance_convergence(scene, lit.pixels, "area", Pattern::Stratified, counts, 256, 5);
  EXPECT_NEAR(stratified.variance_slope, -2.0, 0.15);
  EXPECT_NEAR(stratified.deviation_slope(), stratified.variance_slope / 2, 1e-15);
  // Independent samples: variance = Var(one sample) / N exactly in expectation.
  VarianceConvergence random =
      measure_variance_convergence(scene, lit.pixels, "area", Pattern::Random, counts, 256, 5);
  EXPECT_NEAR(random.variance_slope, -1.0, 0.1);
  ChartSeries series = random.series("random");
  ASSERT_TRUE(series.fit);
  EXPECT_DOUBLE_EQ(series.fit->slope, random.variance_slope);
  EXPECT_THROW(measure_variance_convergence(scene, lit.pixels, "area", Pattern::Random, {4}, 8, 1),
               std::invalid_argument);
  EXPECT_THROW(
      measure_variance_convergence(scene, lit.pixels, "line-nope", Pattern::Random, counts, 8, 1),
      FormatError);
}

class NothingOccludes : public Visibility {
 public:
  bool occluded(const Vec3&, const Vec3&, const Vec3&) const override { return false; }
};

TEST(DiskSquareRejection, UnbiasedAgainstTheOnAxisClosedForm) {
  auto scene = bundled("spheres-plane-disk");
  const Light& disk = scene->lights.at(0);
  ASSERT_EQ(disk.type, LightType::Disk);
  ShadingPoint sp;
  sp.position = {disk.center.x, 0.0, disk.center.z};
  sp.normal = {0, 1, 0};
  sp.wo = normalize(Vec3{0, 1, 1});
  sp.material = &scene->materials.at(0);
  const double h = disk.center.y, r = disk.radius;
  // Lambertian (rho / pi) times the irradiance of a uniform disk on its axis, pi L R^2/(h^2+R^2).
  const double expected = sp.material->albedo.x * disk.radiance.x * r * r / (h * h + r * r);
  NothingOccludes nothing;
  for (Pattern pattern : {Pattern::Random, Pattern::Stratified, Pattern::UniformJitter}) {
    const int trials = 4000;
    double sum = 0, sum_squares = 0;
    for (int t = 0; t < trials; ++t) {
      StreamKey key{17, 3, uint32_t(t), 0};
      double e = estimate_disk_lights_by_square_rejection(*scene, sp, nothing, pattern, key, 16).x;
      ASSERT_TRUE(std::isfinite(e));
      sum += e;
      sum_squares += e * e;
    }
    double mean = sum / trials;
    double standard_error = std::sqrt((sum_squares / trials - mean * mean) / (trials - 1));
    EXPECT_NEAR(mean, expected, 4 * standard_error + 1e-12 * expected)
        << pattern_name(pattern) << ": standard error " << standard_error;
  }
  // Behind the light: nothing.
  sp.position = {0, 4, 0};
  EXPECT_EQ(estimate_disk_lights_by_square_rejection(*scene, sp, nothing, Pattern::Random,
                                                     StreamKey{}, 16)
                .x,
            0.0);
}

TEST(PetersConfigurations, ConvexPlanarAndFacingTheShadingPoint) {
  for (uint64_t index = 0; index < 2000; ++index) {
    std::vector<Vec3> v = random_polygon_configuration(7, index);
    ASSERT_GE(v.size(), 3u);
    ASSERT_LE(v.size(), 8u);
    Vec3 normal = normalize(cross(v[1] - v[0], v[2] - v[0]));
    double size = length(v[1] - v[0]) + length(v[2] - v[1]);
    for (size_t i = 0; i < v.size(); ++i) {
      const Vec3& a = v[i];
      const Vec3& b = v[(i + 1) % v.size()];
      const Vec3& c = v[(i + 2) % v.size()];
      // Planar, and every turn counter-clockwise about the normal: convex.
      EXPECT_LT(std::abs(dot(a - v[0], normal)), 1e-9 * (size + length(v[0]))) << index;
      EXPECT_GE(dot(cross(b - a, c - b), normal), -1e-12 * size * size) << index;
    }
    // The normal (emission side) points towards the shading point at the origin.
    EXPECT_LT(dot(normal, v[0]), 0) << index;
  }
  EXPECT_EQ(random_polygon_configuration(7, 11), random_polygon_configuration(7, 11));
}

TEST(PetersMeasurements, FiniteAndSmallOnAFewConfigurations) {
  PsaVarianceResult variance = measure_psa_relative_deviation(200, 8, 3);
  EXPECT_EQ(variance.configurations, 200);
  EXPECT_EQ(variance.nonfinite_estimates, 0);
  EXPECT_LT(variance.max_relative_deviation, 1e-4);
  BackwardErrorResult backward = measure_psa_backward_error(5000, 2, 3);
  EXPECT_EQ(backward.configurations, 5000);
  EXPECT_EQ(backward.failed_samples, 0);
  EXPECT_LT(backward.max_error, 1e-5);
  EXPECT_LE(backward.p99_error, backward.max_error);
}

}  // namespace
}  // namespace penumbra
