// The exact reference image (see the header): rows in parallel with TBB, camera jitter from the
// renderer's pixel stream, accumulation in the renderer's exact fixed point.

#include "core/exact/exact_reference.h"

#include <pmmintrin.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <xmmintrin.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <ctime>

#include "core/method/direct_lighting.h"
#include "core/render/camera.h"
#include "core/render/local_render.h"
#include "core/render/pixel_filter.h"
#include "core/render/tile.h"
#include "core/sampling/pattern.h"
#include "penumbra/version.h"

namespace penumbra {

ExactReferenceImage render_exact_reference(std::shared_ptr<const Scene> scene,
                                           const ExactReferenceOptions& options) {
  const ExactShading exact(scene, options.shading);
  const CameraRays camera(scene->camera);
  // The renderer's pixel filter (filter importance sampling): the reference's pixel is the same
  // filtered integral as a render's. The default box returns the jitter itself.
  const PixelFilterSampler filter(scene->camera.filter);
  const int width = scene->camera.width, height = scene->camera.height;
  const TileRect rect{0, 0, width, height};
  // Camera samples stratified over the pixel when their count is a square (a pixel across an
  // edge then sees both sides in proportion), else independent.
  uint32_t side = uint32_t(std::lround(std::sqrt(double(options.camera_samples))));
  if (side * side != options.camera_samples) side = 0;
  TileAccumulator sums(rect);
  std::vector<float> fraction(size_t(width) * height, 0.0f);
  std::atomic<uint64_t> exact_count{0}, fallback_count{0};
  struct ThreadState {
    VisibleLightScratch scratch;
    VisibleLightStats stats;
  };
  tbb::enumerable_thread_specific<ThreadState> states;
  const double cpu_start = process_cpu_seconds();
  const auto wall_start = std::chrono::steady_clock::now();
  auto render_rows = [&] {
    tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& rows) {
      _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
      _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
      ThreadState& state = states.local();
      uint64_t exact_here = 0, fallback_here = 0;
      for (int y = rows.begin(); y < rows.end(); ++y)
        for (int x = 0; x < width; ++x) {
          const int64_t pixel = int64_t(y) * width + x;
          uint32_t exact_in_pixel = 0;
          for (uint32_t pass = 0; pass < options.camera_samples; ++pass) {
            StreamKey key{options.seed, uint64_t(pixel), pass, kPixelJitterStream};
            double jx = random_uniform(key, 0, 0), jy = random_uniform(key, 0, 1);
            if (side > 0) {  // stratified: one jittered sample per cell of a side x side grid
              jx = (double(pass % side) + jx) / side;
              jy = (double(pass / side) + jy) / side;
            }
            const Vec2 offset = filter.position(jx, jy);
            const SceneShading::FirstHit hit = exact.shading().first_hit(
                camera.origin(), camera.direction(x + offset.x, y + offset.y));
            const ExactSample sample = exact.radiance(hit, key, state.scratch, &state.stats);
            sums.add_sample(pixel, sample.radiance);
            exact_in_pixel += sample.exact ? 1 : 0;
          }
          fraction[size_t(pixel)] = float(exact_in_pixel) / float(options.camera_samples);
          exact_here += exact_in_pixel;
          fallback_here += options.camera_samples - exact_in_pixel;
        }
      exact_count += exact_here;
      fallback_count += fallback_here;
    });
  };
  if (options.threads > 0) {
    tbb::task_arena arena(options.threads);
    arena.execute(render_rows);
  } else {
    render_rows();
  }
  ExactReferenceImage result;
  result.compute_seconds = process_cpu_seconds() - cpu_start;
  result.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  result.film = assemble_film(width, height, std::span<const TileAccumulator>(&sums, 1));
  result.exact_fraction = Image(width, height);
  for (size_t i = 0; i < fraction.size(); ++i)
    for (int c = 0; c < 3; ++c) result.exact_fraction.rgb[3 * i + c] = fraction[i];
  result.exact_samples = exact_count;
  result.fallback_samples = fallback_count;
  for (const ThreadState& state : states) {
    result.stats.candidates += state.stats.candidates;
    result.stats.projected += state.stats.projected;
    result.stats.contours += state.stats.contours;
  }
  return result;
}

std::vector<float> ExactReferenceImage::fallback_mask() const {
  std::vector<float> mask(size_t(exact_fraction.width) * exact_fraction.height);
  for (size_t i = 0; i < mask.size(); ++i) mask[i] = 1.0f - exact_fraction.rgb[3 * i];
  return mask;
}

double ExactReferenceImage::fallback_pixel_share() const {
  const size_t pixels = size_t(exact_fraction.width) * exact_fraction.height;
  size_t marked = 0;
  for (size_t i = 0; i < pixels; ++i) marked += exact_fraction.rgb[3 * i] < 1.0f ? 1 : 0;
  return pixels > 0 ? double(marked) / double(pixels) : 0.0;
}

std::string encode_exact_reference(const ExactReferenceImage& image,
                                   const ImageMetadata& metadata) {
  return encode_exr(image.film.color, &image.film.variance, metadata,
                    {ExrChannel{kExactMaskChannel, image.fallback_mask()}});
}

ImageMetadata exact_reference_metadata(const Scene& scene, const ExactReferenceOptions& options,
                                       const ExactReferenceImage& image) {
  ImageMetadata metadata;
  metadata["method"] = "exact";
  metadata["fallback_method"] = options.shading.fallback_method;
  metadata["fallback_samples"] = std::to_string(options.shading.fallback_samples);
  metadata["camera_samples"] = std::to_string(options.camera_samples);
  metadata["spp"] = std::to_string(options.camera_samples);
  metadata["seed"] = std::to_string(options.seed);
  metadata["scene"] = scene.name;
  metadata["scene_hash"] = scene.content_hash;
  metadata["compute_seconds"] = std::to_string(image.compute_seconds);
  const double total = double(image.exact_samples + image.fallback_samples);
  metadata["exact_share"] = std::to_string(total > 0 ? double(image.exact_samples) / total : 0.0);
  metadata["fallback_pixel_share"] = std::to_string(image.fallback_pixel_share());
  metadata["mask_channel"] = kExactMaskChannel;
  metadata["build_flavour"] = kBuildFlavour;
  return metadata;
}

}  // namespace penumbra
