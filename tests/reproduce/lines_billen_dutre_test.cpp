// Reproduction of Billen & Dutré 2016 Fig. 9 with the probe (per-point variance over 64
// independent trials, N = 2^k, stratified sampler): on the grid-planes scene, the standard
// deviation of stratified analytic line samples (line-bd16) falls at least as fast as N^-1,
// while stratified solid-angle points fall about as N^-0.72 (the paper: lines -1.15 to -1.27,
// points about -0.72).
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

// Least-squares slope of log(standard deviation) against log(N): half that of the variance.
double std_dev_slope(const std::vector<int>& counts, const std::vector<ProbeRun>& runs) {
  std::vector<double> n(counts.begin(), counts.end()), variance;
  for (const ProbeRun& run : runs) variance.push_back(run.variance.y);
  return 0.5 * log_log_slope(n, variance);
}

TEST(LinesBillenDutre, Fig9StratifiedLinesConvergeFasterThanPoints) {
  auto scene = std::make_shared<const Scene>(
      load_scene(std::string(PENUMBRA_SOURCE_DIR) + "/scenes/grid-planes.json"));
  const Vec3 camera = scene->camera.position;
  const std::vector<int> counts = {4, 8, 16, 32, 64, 128, 256, 512, 1024};
  // Ground points in the grids' shadow: several bars' shadows cross the light from each.
  for (Vec3 position : {Vec3{0.05, 0, 0.1}, Vec3{-0.3, 0, 0.35}}) {
    ProbeSpec spec;
    spec.points = {{position, {0, 1, 0}, normalize(camera - position), "ground"}};
    double lines = std_dev_slope(
        counts,
        run_probe(scene, spec, "line-bd16:u", Pattern::Stratified, counts, 64, 9).points[0]);
    double points = std_dev_slope(
        counts, run_probe(scene, spec, "sa", Pattern::Stratified, counts, 64, 9).points[0]);
    std::printf("fig9 point (%.2f, %.2f): std-dev slope lines %.3f, points %.3f\n", position.x,
                position.z, lines, points);
    EXPECT_LE(lines, -1.0);
    EXPECT_GT(points, -0.9);
    EXPECT_LT(points, -0.55);
  }
}

}  // namespace
}  // namespace penumbra
