// Reproductions of Salesin & Jarosz 2019 with the probe (per-point variance over independent
// trials, N = 2^k samples per term, correlated multi-jittered sampler as in the paper):
//   Fig. 5: MIS of two perpendicular line directions has lower variance than their average at
//           every N (quad-over-floor, a penumbra point by each shadow edge; area and solid-angle
//           lines).
//   Fig. 7: the discontinuity-smoothing heuristic steepens the variance slope of MIS(bsdf, lines):
//           by at least 0.4 at an unoccluded point (paper: -1.4 -> -2.04), and at a partially
//           occluded point too (paper: -1.53 -> -1.68) (glossy-strips: the diffuse base in
//           front of the strips, and a glossy strip in a box's penumbra).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include "core/image/metrics.h"
#include "core/render/probe.h"
#include "core/scene/scene.h"

namespace penumbra {
namespace {

std::shared_ptr<const Scene> bundled(const std::string& name) {
  return std::make_shared<const Scene>(
      load_scene(std::string(PENUMBRA_SOURCE_DIR) + "/scenes/" + name + ".json"));
}

ProbePointSpec point(Vec3 position, Vec3 camera, const std::string& material) {
  // Points on horizontal surfaces facing up, seen from the camera.
  return {position, {0, 1, 0}, normalize(camera - position), material};
}

// Variance (green channel) at each N for one point.
std::vector<double> variances(std::shared_ptr<const Scene> scene, const ProbePointSpec& p,
                              const std::string& method, const std::vector<int>& counts,
                              int trials) {
  ProbeSpec spec;
  spec.points = {p};
  ProbeResult result = run_probe(scene, spec, method, Pattern::Cmj, counts, trials, 2019);
  std::vector<double> out;
  for (const ProbeRun& run : result.points[0]) out.push_back(run.variance.y);
  return out;
}

// Least-squares slope of log(variance) against log(N).
double slope(const std::vector<int>& counts, const std::vector<double>& variance) {
  return log_log_slope(std::vector<double>(counts.begin(), counts.end()), variance);
}

TEST(LinesSalesinJarosz, Fig5MisOfTwoLineDirectionsBeatsTheirAverageAtEveryN) {
  auto scene = bundled("quad-over-floor");
  const Vec3 camera = scene->camera.position;
  const std::vector<int> counts = {1, 2, 4, 8, 16, 32, 64};
  // Penumbra points by the occluder's shadow edge parallel to edge1 (x) and to edge2 (z).
  for (const ProbePointSpec& p :
       {point({0.02, 0, 0.33}, camera, "floor"), point({0.33, 0, 0.02}, camera, "floor")}) {
    for (const char* lines : {"line-area", "line-sa"}) {
      std::string both = std::string(lines) + ":u+" + lines + ":v";
      std::vector<double> mis = variances(scene, p, both + "/balance", counts, 128);
      std::vector<double> avg = variances(scene, p, both + "/avg", counts, 128);
      for (size_t i = 0; i < counts.size(); ++i) {
        std::printf("fig5 %s point (%.2f, %.2f) N=%d: mis %.4g avg %.4g\n", lines, p.position.x,
                    p.position.z, counts[i], mis[i], avg[i]);
        EXPECT_LT(mis[i], avg[i]) << both << " at N = " << counts[i];
      }
    }
  }
}

TEST(LinesSalesinJarosz, Fig7SmoothingSteepensTheVarianceSlopeOfMisWithTheBsdf) {
  auto scene = bundled("glossy-strips");
  const Vec3 camera = scene->camera.position;
  // N = 4^k: square strata for every term (no leftover samples in the cmj grid).
  const std::vector<int> counts = {4, 16, 64, 256, 1024, 4096};
  struct Case {
    const char* what;
    ProbePointSpec p;
    double min_gain;  // how much steeper the smoothed slope must be
  };
  const Case cases[] = {
      {"unoccluded", point({0.05, -0.001, 1.4}, camera, "base"), 0.4},
      {"partly occluded", point({0.05, 0, 0.1}, camera, "strip-4"), 0.0},
  };
  for (const Case& c : cases) {
    std::vector<double> plain = variances(scene, c.p, "bsdf+line-sa:v", counts, 128);
    std::vector<double> smooth = variances(scene, c.p, "bsdf+line-sa:v/smooth", counts, 128);
    double plain_slope = slope(counts, plain), smooth_slope = slope(counts, smooth);
    std::printf("fig7 %s: slope balance %.3f, smooth %.3f (variance at N=%d: %.4g vs %.4g)\n",
                c.what, plain_slope, smooth_slope, counts.back(), plain.back(), smooth.back());
    EXPECT_LT(smooth_slope, plain_slope - c.min_gain) << c.what;
  }
}

}  // namespace
}  // namespace penumbra
