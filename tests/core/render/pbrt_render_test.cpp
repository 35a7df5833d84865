// pbrt-v3 scenes through the renderer: the peer Cornell box renders bit-identically to its JSON
// twin; the pbrt camera's mirrored axis, screen window and crop; filter importance sampling
// draws positions with the pixel filter's density (chi-square).

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <fstream>
#include <random>
#include <sstream>

#include "core/render/camera.h"
#include "core/render/pixel_filter.h"
#include "core/render/renderer.h"
#include "core/scene/scene.h"
#include "tests/support/peer_scenes.h"

namespace penumbra {
namespace {

const std::string kSource = PENUMBRA_SOURCE_DIR;

std::shared_ptr<const Scene> load(const std::string& path) {
  return std::make_shared<const Scene>(load_scene(path));
}

TileAccumulator render_image(const std::shared_ptr<const Scene>& scene, const std::string& method,
                             uint32_t passes) {
  Renderer renderer(scene, RenderOptions{method, Pattern::Random, 7});
  TileRect rect{0, 0, scene->camera.width, scene->camera.height};
  TileAccumulator out(rect);
  renderer.render_tile(rect, 0, passes, out);
  return out;
}

// The same triangles, camera and light give the same rays and so the same bits: the pbrt
// file's transform is a permutation with signs (exact in double), its numbers are read as
// doubles like the JSON's, and its box filter of radius 0.5 is the JSON camera's pixel jitter.
TEST(PbrtRender, CornellBoxIsBitIdenticalToItsJsonTwin) {
  auto pbrt = load(kSource + "/tests/data/pbrt/cornell-box.pbrt");
  auto json = load(kSource + "/scenes/cornell-box.json");
  EXPECT_EQ(pbrt->positions, json->positions);
  EXPECT_EQ(pbrt->indices, json->indices);
  EXPECT_EQ(pbrt->render_defaults.method, "line-area:v+line-area:u/balance");
  EXPECT_EQ(pbrt->render_defaults.sampler, "random");
  EXPECT_EQ(pbrt->render_defaults.spp, 16u);
  for (const char* method : {"line-area:u+line-area:v/balance", "bsdf+sa"}) {
    SCOPED_TRACE(method);
    EXPECT_TRUE(render_image(pbrt, method, 1) == render_image(json, method, 1));
  }
}

// The committed copy is the peer scene byte for byte.
TEST(PbrtRender, CommittedCornellBoxIsThePeerFile) {
  const std::string peer = testing::peer_scene("cornell-box/cornell-box.pbrt");
  if (peer.empty()) GTEST_SKIP() << testing::peer_scene_missing("cornell-box/cornell-box.pbrt");
  auto bytes = [](const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
  };
  EXPECT_EQ(bytes(peer), bytes(kSource + "/tests/data/pbrt/cornell-box.pbrt"));
}

TEST(PbrtRender, MirroredCameraAndCropGiveThePbrtRays) {
  Camera camera;
  camera.position = {0, 0, 5};
  camera.look_at = {0, 0, 4};
  camera.width = 100;
  camera.height = 50;
  camera.fov_y_deg = 40;
  CameraRays plain(camera);
  Camera mirrored = camera;
  mirrored.mirror_x = true;
  CameraRays flipped(mirrored);
  Vec3 a = plain.direction(10.25, 20.5), b = flipped.direction(10.25, 20.5);
  EXPECT_DOUBLE_EQ(a.x, -b.x);
  EXPECT_DOUBLE_EQ(a.y, b.y);
  // A crop of the right half, lower half: its pixel (0, 0) is the full frame's (50, 25).
  Camera crop = camera;
  crop.width = 50;
  crop.height = 25;
  crop.crop_x = 50;
  crop.crop_y = 25;
  crop.full_width = 100;
  crop.full_height = 50;
  crop.screen_x0 = -2;
  crop.screen_x1 = 2;
  CameraRays cropped(crop);
  Vec3 full = plain.direction(50.5, 25.5), part = cropped.direction(0.5, 0.5);
  for (int axis = 0; axis < 3; ++axis) EXPECT_NEAR(full[axis], part[axis], 1e-15);
}

// Samples of each filter against its density: chi-square over 24 equal bins of [-r, r].
TEST(PixelFilterSampling, PositionsFollowTheFilter) {
  for (PixelFilterType type :
       {PixelFilterType::Box, PixelFilterType::Triangle, PixelFilterType::Gaussian}) {
    PixelFilter filter;
    filter.type = type;
    filter.radius_x = 1.5;
    filter.radius_y = 1;
    filter.alpha = 2;
    PixelFilterSampler sampler(filter);
    const int bins = 24, samples = 200000;
    std::vector<int> counts(bins, 0);
    std::mt19937_64 random(5);
    std::uniform_real_distribution<double> uniform(0, 1);
    for (int i = 0; i < samples; ++i) {
      Vec2 p = sampler.position(uniform(random), uniform(random));
      double x = p.x - 0.5;  // offset from the pixel centre, in [-1.5, 1.5]
      ASSERT_GE(x, -1.5);
      ASSERT_LE(x, 1.5);
      ASSERT_GE(p.y - 0.5, -1);
      ASSERT_LE(p.y - 0.5, 1);
      counts[std::min(bins - 1, int((x + 1.5) / 3.0 * bins))]++;
    }
    double chi2 = 0;
    for (int b = 0; b < bins; ++b) {
      // Expected probability of the bin: Simpson's rule on the density.
      double x0 = -1.5 + 3.0 * b / bins, x1 = x0 + 3.0 / bins;
      double probability = 0;
      const int steps = 64;
      for (int k = 0; k <= steps; ++k) {
        double w = (k == 0 || k == steps) ? 1 : (k % 2 ? 4 : 2);
        probability += w * sampler.density(x0 + (x1 - x0) * k / steps, 0);
      }
      probability *= (x1 - x0) / (3.0 * steps);
      double expected = probability * samples;
      chi2 += (counts[b] - expected) * (counts[b] - expected) / expected;
    }
    // 23 degrees of freedom: P(chi2 > 55) < 2e-4.
    EXPECT_LT(chi2, 55) << "filter type " << int(type);
  }
}

TEST(PixelFilterSampling, TheDefaultBoxIsTheJsonJitter) {
  PixelFilterSampler sampler{PixelFilter{}};
  Vec2 p = sampler.position(0.123456789, 0.987654321);
  EXPECT_EQ(p.x, 0.123456789);
  EXPECT_EQ(p.y, 0.987654321);
}

}  // namespace
}  // namespace penumbra
