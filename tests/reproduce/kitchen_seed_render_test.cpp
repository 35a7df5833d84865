// Penumbra's render of the peer kitchen (kitchen-play.pbrt: 1.44M triangles, textures, glass,
// metal, a window light) against what the seed system renders for the same file
// (../shared/peer-scenes/kitchen/seed-system-render.exr: 1280x720, its own method, 3x3 pixel
// samples, a box filter of radius 1). Both estimate the same image, so their block means may
// differ by noise only.
//
// The statistic. The image is cut into 16x16-pixel blocks; half of them (a checkerboard over the
// whole frame) are rendered by Penumbra with the file's own method at 2 samples per pixel
// (random sampler, so per-pixel sample variances are unbiased). Per block and channel,
// d = seed mean - Penumbra mean, and
//   Var(d) = V_P + V_S + floor^2,
//   V_P = sum over pixels of Penumbra's variance of the pixel mean / 256^2 (pixels independent:
//         filter importance sampling gives each pixel its own samples);
//   V_S = mean per-sample variance / (9 * 256): the seed's noise, modelled as the same estimator
//         with 9 samples per pixel. pbrt-v3 splats each sample into the 2x2 pixels its radius-1
//         box covers, so neighbouring seed pixels share samples and a block holds 9 * 256
//         independent samples, not 4x as many. The seed places its camera samples on a fixed 3x3
//         grid per pixel (its samplers' "fixedpixels", on by default) and stratifies its light
//         samples, which only lowers its true variance: V_S errs on the large side (mean z^2
//         comes out near 0.5).
//   floor = 0.2% of the image mean: block differences that small are not resolved. The fixed
//         grid makes the seed's block means a quadrature of the block integral rather than an
//         estimate of it (off by a fraction of a pixel's coverage along sharp edges, such as the
//         window frame in front of the light), and a 2-sample Penumbra block can miss a rare
//         contribution altogether (zero sample variance where the seed shows a few lit pixels).
// z = d / sqrt(Var(d)). Per channel, the mean of the blocks' z must be within 3.5 of its
// standard errors of 0 (a t statistic: it does not depend on the scale of the variance model),
// few blocks may lie beyond 5 standard deviations, and the mean z^2 must stay below 1.5. Then the
// same blocks are rendered with the walls' albedo lowered 5% (the largest material in view) and
// the same statistic must reject that scene, so the test can fail.
//
// Cost: one scene load (~5 s), two renders of 920k camera samples each.

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "core/image/image.h"
#include "core/render/renderer.h"
#include "core/scene/scene.h"
#include "tests/support/peer_scenes.h"

namespace penumbra {
namespace {

constexpr int kBlock = 16;
constexpr uint32_t kSpp = 2;
constexpr double kSeedSpp = 9;
// Acceptance: |t| of the blocks' mean z (about N(0, 1) when the renders agree, whatever the
// scale of the variance model: P(|t| > 3.5) = 5e-4 per channel); few blocks beyond 5 standard
// deviations; mean z^2 not far above 1 (the variance model errs on the large side).
constexpr double kMaxT = 3.5;
constexpr double kMaxOutlierShare = 0.005;
constexpr double kMaxMeanZ2 = 1.5;

struct BlockStats {
  Rgb seed, penumbra, variance;  // block means and Var(seed - penumbra)
  int x = 0, y = 0;              // the block's top-left pixel
};

// Renders the chosen blocks and pairs each with the seed image's block mean.
std::vector<BlockStats> compare_blocks(const std::shared_ptr<const Scene>& scene, const Image& seed,
                                       const std::string& method) {
  Renderer renderer(scene, RenderOptions{method, Pattern::Random, 11});
  std::vector<BlockStats> out;
  const int bw = scene->camera.width / kBlock, bh = scene->camera.height / kBlock;
  for (int by = 0; by < bh; ++by)
    for (int bx = by % 2; bx < bw; bx += 2) {
      TileRect rect{bx * kBlock, by * kBlock, (bx + 1) * kBlock, (by + 1) * kBlock};
      TileAccumulator acc(rect);
      renderer.render_tile(rect, 0, kSpp, acc);
      EXPECT_EQ(acc.nonfinite_samples(), 0u);
      BlockStats s;
      s.x = rect.x0;
      s.y = rect.y0;
      Rgb per_sample{0, 0, 0}, var_p{0, 0, 0};
      const double n = double(kBlock) * kBlock;
      for (int64_t i = 0; i < rect.pixel_count(); ++i) {
        s.penumbra = s.penumbra + acc.mean(i) / n;
        Rgb v = acc.variance_of_mean(i);
        var_p = var_p + v / (n * n);
        per_sample = per_sample + v * double(acc.count(i)) / n;
        int x = rect.x0 + int(i % kBlock), y = rect.y0 + int(i / kBlock);
        s.seed = s.seed + seed.at(x, y) / n;
      }
      s.variance = var_p + per_sample / (kSeedSpp * n);
      out.push_back(s);
    }
  return out;
}

struct Verdict {
  double t = 0;              // largest |t| over channels: mean z / (its standard error)
  double outlier_share = 0;  // share of (block, channel) pairs with |z| > 5
  double mean_z2 = 0;        // mean z^2 over blocks and channels
};

// `floor`: a standard deviation added to every block's (see the file comment).
Verdict judge(const std::vector<BlockStats>& blocks, double floor) {
  Verdict v;
  const double k = double(blocks.size());
  int outliers = 0;
  for (int c = 0; c < 3; ++c) {
    double sum_z = 0, sum_z2 = 0;
    for (const BlockStats& b : blocks) {
      double d = b.seed[c] - b.penumbra[c], var = b.variance[c] + floor * floor;
      double z = d / std::sqrt(var);
      sum_z += z;
      sum_z2 += z * z;
      if (z * z > 25) {
        ++outliers;
        if (std::getenv("KITCHEN_DEBUG"))
          std::printf("(%d,%d) c%d seed %.5g penumbra %.5g sd %.3g z %.3g\n", b.x, b.y, c,
                      b.seed[c], b.penumbra[c], std::sqrt(var), z);
      }
    }
    double mean = sum_z / k, spread = std::sqrt((sum_z2 - k * mean * mean) / (k - 1));
    v.t = std::max(v.t, std::abs(mean) / (spread / std::sqrt(k)));
    v.mean_z2 += sum_z2 / (3 * k);
  }
  v.outlier_share = outliers / (3 * k);
  return v;
}

TEST(KitchenSeedRender, BlockMeansAgreeWithTheSeedSystemWithinNoise) {
  const std::string file = testing::peer_scene("kitchen/kitchen-play.pbrt");
  const std::string seed_file = testing::peer_scene("kitchen/seed-system-render.exr");
  if (file.empty() || seed_file.empty())
    GTEST_SKIP() << testing::peer_scene_missing("kitchen/seed-system-render.exr");
  auto t0 = std::chrono::steady_clock::now();
  Scene loaded = load_scene(file);
  const Image seed = read_exr(seed_file);
  ASSERT_EQ(seed.width, loaded.camera.width);
  ASSERT_EQ(seed.height, loaded.camera.height);
  // The seed render used 3x3 pixel samples; pbrt-v3 scales the texture footprint by
  // 1 / sqrt(samples per pixel).
  loaded.texture_footprint_scale = 1.0 / 3.0;
  const std::string method = loaded.render_defaults.method;
  ASSERT_FALSE(method.empty());
  auto scene = std::make_shared<const Scene>(loaded);
  auto t1 = std::chrono::steady_clock::now();

  std::vector<BlockStats> blocks = compare_blocks(scene, seed, method);
  double image_mean = 0;
  for (float value : seed.rgb) image_mean += value / double(seed.rgb.size());
  const double floor = 0.002 * image_mean;
  Verdict same = judge(blocks, floor);
  auto t2 = std::chrono::steady_clock::now();
  std::printf(
      "kitchen (%s, %zu blocks of %dx%d, %u spp): |t| %.2f, |z| > 5 share %.4f, "
      "mean z^2 %.3f; load %.1f s, render %.1f s\n",
      method.c_str(), blocks.size(), kBlock, kBlock, kSpp, same.t, same.outlier_share, same.mean_z2,
      std::chrono::duration<double>(t1 - t0).count(),
      std::chrono::duration<double>(t2 - t1).count());
  EXPECT_LT(same.t, kMaxT);
  EXPECT_LT(same.outlier_share, kMaxOutlierShare);
  EXPECT_LT(same.mean_z2, kMaxMeanZ2);

  if (std::getenv("KITCHEN_DEBUG")) return;
  // The same blocks with the walls 5% darker: the statistic must see it.
  Scene darker = loaded;
  bool found = false;
  for (Material& m : darker.materials)
    if (m.name == "Walls") {
      // A constant matte is read as the exact Lambert material; its albedo is its Kd.
      ASSERT_EQ(m.type, MaterialType::Lambert);
      m.albedo = m.albedo * 0.95;
      found = true;
    }
  ASSERT_TRUE(found);
  Verdict perturbed =
      judge(compare_blocks(std::make_shared<const Scene>(darker), seed, method), floor);
  std::printf("walls' Kd x 0.95: |t| %.2f, |z| > 5 share %.4f, mean z^2 %.3f\n", perturbed.t,
              perturbed.outlier_share, perturbed.mean_z2);
  EXPECT_TRUE(perturbed.t > kMaxT || perturbed.outlier_share > kMaxOutlierShare ||
              perturbed.mean_z2 > kMaxMeanZ2);
}

}  // namespace
}  // namespace penumbra
