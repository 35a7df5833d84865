// The exact reference's fallback mask (core/exact/exact_reference.h) on a scene that mixes
// Lambertian and GGX surfaces: the EXR's exact.mask channel is, per pixel, the share of its
// camera samples that hit a non-Lambertian surface (recomputed here from the same camera rays
// and the hit materials), and the pixels the mask calls exact match a brute-force estimate at
// the same camera samples (solid-angle sampling with 32 x 256 samples per sample, ray-traced
// visibility) within 5 standard errors of that estimate.

#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "core/exact/exact_reference.h"
#include "core/method/direct_lighting.h"
#include "core/method/method.h"
#include "core/render/camera.h"
#include "core/render/pixel_filter.h"
#include "core/render/shading.h"
#include "core/render/tile.h"
#include "core/sampling/pattern.h"

namespace penumbra {
namespace {

// A floor, its left half Lambertian and its right half GGX, a Lambertian plate casting a
// penumbra across both halves and a GGX box standing on the Lambertian half, under a quad light.
const char* kScene = R"({
  "format": "penumbra/scene@1", "name": "mask-test",
  "camera": { "position": [0, 1.6, 2.6], "look_at": [0, 0.1, 0], "up": [0, 1, 0],
              "fov_y_deg": 45, "width": 20, "height": 14 },
  "materials": {
    "matte": { "type": "lambert", "albedo": [0.7, 0.6, 0.5] },
    "glossy": { "type": "ggx", "diffuse": [0.4, 0.4, 0.4], "specular": [0.3, 0.3, 0.3],
                "roughness": 0.35 }
  },
  "shapes": [
    { "type": "quad", "origin": [-1.5, 0, 1.5], "edge1": [1.5, 0, 0], "edge2": [0, 0, -3], "material": "matte" },
    { "type": "quad", "origin": [0, 0, 1.5], "edge1": [1.5, 0, 0], "edge2": [0, 0, -3], "material": "glossy" },
    { "type": "quad", "origin": [-0.3, 0.6, -0.2], "edge1": [0.6, 0, 0], "edge2": [0, 0, 0.3], "material": "matte" },
    { "type": "box", "min": [-0.9, 0, 0.3], "max": [-0.6, 0.3, 0.6], "material": "glossy" }
  ],
  "lights": [ { "type": "quad", "origin": [-0.4, 1.4, -0.4], "edge1": [0.8, 0, 0],
                "edge2": [0, 0, 0.8], "radiance": [6, 6, 6] } ]
})";

TEST(ExactMask, MarksTheNonLambertianCameraSamplesAndExactPixelsMatchBruteForce) {
  auto scene = std::make_shared<const Scene>(parse_scene(kScene, "."));
  ExactReferenceOptions options;
  options.camera_samples = 4;  // a 2 x 2 grid per pixel
  options.shading.fallback_samples = 16;
  options.threads = 2;
  const ExactReferenceImage image = render_exact_reference(scene, options);
  const std::string exr =
      encode_exact_reference(image, exact_reference_metadata(*scene, options, image));
  const std::vector<float> mask = decode_exr_channel(exr, kExactMaskChannel);
  const int width = scene->camera.width, height = scene->camera.height;
  ASSERT_EQ(mask.size(), size_t(width) * height);

  // The same camera rays as the reference (its jitter streams and 2 x 2 strata), classified by
  // the hit's material; and at each Lambertian hit a brute-force estimate of its radiance.
  const SceneShading brute(scene, parse_method("sa"));
  const CameraRays camera(scene->camera);
  const PixelFilterSampler filter(scene->camera.filter);
  constexpr int kBatches = 32, kPerBatch = 256;
  int exact_pixels = 0, mixed_pixels = 0, fallback_pixels = 0;
  double worst_z = 0;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const int64_t pixel = int64_t(y) * width + x;
      int non_lambertian = 0;
      Rgb batch_means[kBatches] = {};
      for (uint32_t pass = 0; pass < options.camera_samples; ++pass) {
        const StreamKey key{options.seed, uint64_t(pixel), pass, kPixelJitterStream};
        const double jx = (double(pass % 2) + random_uniform(key, 0, 0)) / 2;
        const double jy = (double(pass / 2) + random_uniform(key, 0, 1)) / 2;
        const Vec2 offset = filter.position(jx, jy);
        const SceneShading::FirstHit hit =
            brute.first_hit(camera.origin(), camera.direction(x + offset.x, y + offset.y));
        const bool lambertian =
            !hit.shading_point || hit.shading_point->material->type == MaterialType::Lambert;
        non_lambertian += lambertian ? 0 : 1;
        for (int b = 0; b < kBatches; ++b) {
          Rgb value = hit.emitted;
          if (hit.shading_point && lambertian) {
            const StreamKey batch_key{9000 + uint64_t(b), uint64_t(pixel), pass, 0};
            value = brute.direct_lighting().estimate(*hit.shading_point, brute, Pattern::Stratified,
                                                     batch_key, kPerBatch);
          }
          batch_means[b] += value * (1.0 / options.camera_samples);
        }
      }
      const float expected = float(non_lambertian) / float(options.camera_samples);
      EXPECT_FLOAT_EQ(mask[size_t(pixel)], expected) << "pixel (" << x << ", " << y << ")";
      if (non_lambertian == int(options.camera_samples)) ++fallback_pixels;
      if (non_lambertian > 0) {
        if (non_lambertian < int(options.camera_samples)) ++mixed_pixels;
        continue;
      }
      ++exact_pixels;
      // The exact pixel against the brute-force mean, per channel, in standard errors of it.
      const Rgb reference = image.film.color.at(x, y);
      for (int c = 0; c < 3; ++c) {
        double mean = 0, squares = 0;
        for (const Rgb& m : batch_means) mean += m[c] / kBatches;
        for (const Rgb& m : batch_means) squares += (m[c] - mean) * (m[c] - mean);
        const double standard_error = std::sqrt(squares / (kBatches - 1) / kBatches);
        const double z =
            std::abs(reference[c] - mean) / (standard_error + 1e-7 * std::abs(mean) + 1e-12);
        worst_z = std::max(worst_z, z);
        EXPECT_LT(z, 5.0) << "pixel (" << x << ", " << y << ") channel " << c << ": exact "
                          << reference[c] << ", brute force " << mean << " +- " << standard_error;
      }
    }
  std::printf("%d exact, %d mixed, %d fallback pixels; worst |z| %.2f\n", exact_pixels,
              mixed_pixels, fallback_pixels, worst_z);
  // The scene has all three kinds, and the metadata's share agrees with the mask.
  EXPECT_GT(exact_pixels, 20);
  EXPECT_GT(mixed_pixels, 0);
  EXPECT_GT(fallback_pixels, 20);
  EXPECT_NEAR(image.fallback_pixel_share(),
              double(mixed_pixels + fallback_pixels) / double(width * height), 1e-12);
}

}  // namespace
}  // namespace penumbra
