// Peters 2021 Sec. 4.3 / Fig. 10 on the bundled occluded-planes scene, through the probe
// (core/render/probe.h, 1024 trials at N = 1 and 4): in the penumbra, at a pixel where the white
// glossy plane's specular lobe falls on the partly occluded light, `psa+ltc/clamped-optimal` has
// lower variance than `psa+ltc/balance` (and all combinations agree on the mean).
//
// The pixel is chosen by the test, not by hand, among the pixels of the scene's
// `glossy-penumbra` region: the camera ray must hit the white glossy plane, the mirror direction
// of the view must meet the light (the lobe falls on it), and 60% to 95% of the light must be
// visible (a penumbra: the wall hides the rest); of those, the one closest to 80% visible.
//
// Why not deeper in the penumbra: a scan of the region (penumbra probe, 256 trials, N = 1) found
// clamped optimal ahead of balance by 0.81-0.92x in variance where most of the light and the
// highlight on it are visible (the bottom rows of the region), but BEHIND balance by up to 1.47x
// where half or less of the light is visible (e.g. pixel (304, 434), 54% visible: 2.60 vs 2.31;
// rows near the wall: 1.4-1.47x). There the part of the highlight that c_1 promises is hidden,
// so the weighted half of the blend over-trusts the ltc samples; Peters' v = 1/2 stands for an
// estimate of visibility (his Supplement B), and his claim is robustness across the image, not a
// win at every pixel. In a diffuse penumbra (the blue plane) balance also wins (the weighted
// heuristic nearly ignores the ltc samples there, c_1 ~ 0): we print the blue plane's figures and
// only require clamped optimal to stay within 1.5x of balance and ahead of plain weighted.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>

#include "core/render/camera.h"
#include "core/render/probe.h"
#include "core/render/shading.h"
#include "core/scene/scene.h"

namespace penumbra {
namespace {

std::shared_ptr<const Scene> occluded_planes() {
  return std::make_shared<const Scene>(load_scene(
      (std::filesystem::path(PENUMBRA_SOURCE_DIR) / "scenes" / "occluded-planes.json").string()));
}

// Fraction of a k x k grid of points on the (quad) light that the shading point sees.
double visible_fraction(const SceneShading& shading, const Light& light, const ShadingPoint& sp,
                        int k = 24) {
  int visible = 0;
  for (int i = 0; i < k; ++i)
    for (int j = 0; j < k; ++j) {
      Vec3 p = light.origin + light.edge1 * ((i + 0.5) / k) + light.edge2 * ((j + 0.5) / k);
      visible += !shading.occluded(sp.position, sp.normal, p);
    }
  return double(visible) / (k * k);
}

// Does the mirror direction of wo meet the light (inside the quad)?
bool mirror_hits_light(const Light& light, const ShadingPoint& sp) {
  Vec3 r = 2.0 * dot(sp.normal, sp.wo) * sp.normal - sp.wo;
  double denominator = dot(light.normal, r);
  if (!(denominator < 0)) return false;
  double t = dot(light.normal, light.origin - sp.position) / denominator;
  Vec3 q = sp.position + r * t - light.origin;
  double s = dot(q, light.edge1) / length_squared(light.edge1);
  double u = dot(q, light.edge2) / length_squared(light.edge2);
  return t > 0 && s > 0.1 && s < 0.9 && u > 0.1 && u < 0.9;
}

struct Candidate {
  int x = 0, y = 0;
  double visible = 0;
};

std::optional<Candidate> find_pixel(const std::shared_ptr<const Scene>& scene,
                                    const std::string& region_name,
                                    const std::string& material_name, bool need_mirror,
                                    double min_visible, double max_visible, double target) {
  SceneShading shading(scene, parse_method("sa"));
  CameraRays camera(scene->camera);
  const Light& light = scene->lights.at(0);
  const Region& region = scene->regions.at(region_name);
  std::optional<Candidate> best;
  // Scan the region every 4 pixels; keep the candidate with visibility closest to the target.
  for (int y = region.y0; y < region.y1; y += 4)
    for (int x = region.x0; x < region.x1; x += 4) {
      auto hit = shading.first_hit(camera.origin(), camera.direction(x + 0.5, y + 0.5));
      if (!hit.shading_point || hit.shading_point->material->name != material_name) continue;
      if (need_mirror && !mirror_hits_light(light, *hit.shading_point)) continue;
      double v = visible_fraction(shading, light, *hit.shading_point);
      if (v < min_visible || v > max_visible) continue;
      if (!best || std::abs(v - target) < std::abs(best->visible - target))
        best = Candidate{x, y, v};
    }
  return best;
}

struct Variances {
  double balance = 0, clamped = 0, weighted = 0;
};

Variances probe_variances(const std::shared_ptr<const Scene>& scene, const Candidate& pixel,
                          const char* what) {
  ProbeSpec spec;
  spec.pixels.push_back({pixel.x, pixel.y});
  const int trials = 1024;
  const int counts[] = {1, 4};
  Variances total;
  ProbeResult balance =
      run_probe(scene, spec, "psa+ltc/balance", Pattern::Random, counts, trials, 3);
  ProbeResult clamped =
      run_probe(scene, spec, "psa+ltc/clamped-optimal", Pattern::Random, counts, trials, 3);
  ProbeResult weighted =
      run_probe(scene, spec, "psa+ltc/weighted", Pattern::Random, counts, trials, 3);
  for (size_t k = 0; k < std::size(counts); ++k) {
    const ProbeRun& b = balance.points[0][k];
    const ProbeRun& c = clamped.points[0][k];
    const ProbeRun& w = weighted.points[0][k];
    auto sum = [](const Rgb& v) { return v.x + v.y + v.z; };
    std::printf(
        "%s pixel (%d, %d), %.0f%% of the light visible, N = %d: mean %.4g / %.4g / %.4g, "
        "variance balance %.4g, clamped-optimal %.4g, weighted %.4g\n",
        what, pixel.x, pixel.y, 100 * pixel.visible, counts[k], sum(b.mean), sum(c.mean),
        sum(w.mean), sum(b.variance), sum(c.variance), sum(w.variance));
    // The same integral: means within 6 standard errors of their difference.
    for (int ch = 0; ch < 3; ++ch) {
      double se = std::sqrt((b.variance[ch] + c.variance[ch]) / trials);
      EXPECT_NEAR(b.mean[ch], c.mean[ch], 6 * se + 1e-12) << what << " N " << counts[k];
      double se_w = std::sqrt((b.variance[ch] + w.variance[ch]) / trials);
      EXPECT_NEAR(b.mean[ch], w.mean[ch], 6 * se_w + 1e-12) << what << " N " << counts[k];
    }
    total.balance += sum(b.variance);
    total.clamped += sum(c.variance);
    total.weighted += sum(w.variance);
  }
  return total;
}

TEST(PetersProbe, ClampedOptimalBeatsBalanceInTheGlossyPenumbraOfOccludedPlanes) {
  auto scene = occluded_planes();
  std::optional<Candidate> glossy =
      find_pixel(scene, "glossy-penumbra", "white-glossy", true, 0.6, 0.95, 0.8);
  ASSERT_TRUE(glossy.has_value()) << "no pixel of glossy-penumbra sees its highlight on the "
                                     "partly occluded light";
  Variances v = probe_variances(scene, *glossy, "glossy penumbra");
  // Sums over N = 1 and N = 4 and the channels; 1024 trials each (the variance estimates carry a
  // few % relative noise): require a margin beyond it.
  EXPECT_LT(v.clamped, 0.93 * v.balance);
}

TEST(PetersProbe, ClampedOptimalStaysCloseToBalanceInTheDiffusePenumbra) {
  auto scene = occluded_planes();
  std::optional<Candidate> diffuse =
      find_pixel(scene, "diffuse-penumbra", "blue", false, 0.3, 0.7, 0.5);
  ASSERT_TRUE(diffuse.has_value());
  Variances v = probe_variances(scene, *diffuse, "diffuse penumbra");
  EXPECT_LT(v.clamped, 1.5 * v.balance);
  EXPECT_LT(v.clamped, v.weighted);
}

}  // namespace
}  // namespace penumbra
