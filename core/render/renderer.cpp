#include "core/render/renderer.h"

#include <pmmintrin.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <xmmintrin.h>

#include <stdexcept>

#include "core/render/camera.h"
#include "core/render/pixel_filter.h"
#include "core/render/shading.h"

namespace penumbra {

struct Renderer::Impl {
  Impl(std::shared_ptr<const PreparedScene> prepared, const RenderOptions& options,
       const MethodSpec& method)
      : options(options),
        shading(prepared, method),
        camera(prepared->scene().camera),
        filter(prepared->scene().camera.filter) {}
  RenderOptions options;
  SceneShading shading;
  CameraRays camera;
  PixelFilterSampler filter;
};

Renderer::Renderer(std::shared_ptr<const Scene> scene, const RenderOptions& options)
    : impl_(std::make_unique<Impl>(std::make_shared<const PreparedScene>(std::move(scene)), options,
                                   parse_method(options.method))) {}

Renderer::Renderer(std::shared_ptr<const PreparedScene> prepared, const RenderOptions& options)
    : impl_(std::make_unique<Impl>(std::move(prepared), options, parse_method(options.method))) {}

Renderer::Renderer(std::shared_ptr<const PreparedScene> prepared, const RenderOptions& options,
                   const MethodSpec& method)
    : impl_(std::make_unique<Impl>(std::move(prepared), options, method)) {}

Renderer::~Renderer() = default;

const Scene& Renderer::scene() const {
  return impl_->shading.scene();
}
const RenderOptions& Renderer::options() const {
  return impl_->options;
}

void Renderer::render_tile(const TileRect& tile, uint32_t pass_begin, uint32_t pass_end,
                           TileAccumulator& out) const {
  if (!(out.rect() == tile)) throw std::invalid_argument("render_tile: accumulator rect differs");
  const Scene& scene = impl_->shading.scene();
  const int width = scene.camera.width;
  tbb::parallel_for(
      tbb::blocked_range<int>(tile.y0, tile.y1), [&](const tbb::blocked_range<int>& rows) {
        // Embree wants flush-to-zero and denormals-are-zero on every thread that traces.
        _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
        _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
        for (int y = rows.begin(); y < rows.end(); ++y) {
          for (int x = tile.x0; x < tile.x1; ++x) {
            int64_t local = int64_t(y - tile.y0) * tile.width() + (x - tile.x0);
            StreamKey key{impl_->options.seed, uint64_t(y) * width + x, 0, kPixelJitterStream};
            for (uint32_t pass = pass_begin; pass < pass_end; ++pass) {
              key.pass = pass;
              key.stream = kPixelJitterStream;
              // The sample's place in the pixel, drawn from the pixel filter.
              Vec2 offset =
                  impl_->filter.position(random_uniform(key, 0, 0), random_uniform(key, 0, 1));
              Vec3 direction = impl_->camera.direction(x + offset.x, y + offset.y);
              const Vec3& origin = impl_->camera.origin();
              RayDifferential differential;
              bool with_differential = impl_->shading.wants_differentials();
              if (with_differential) {
                // The rays one pixel over, scaled as pbrt-v3's samplers scale them.
                double scale = scene.texture_footprint_scale;
                Vec3 dx = impl_->camera.direction(x + offset.x + 1, y + offset.y);
                Vec3 dy = impl_->camera.direction(x + offset.x, y + offset.y + 1);
                differential = {origin, direction + (dx - direction) * scale, origin,
                                direction + (dy - direction) * scale};
              }
              Rgb radiance =
                  impl_->shading.radiance(origin, direction, impl_->options.sampler, key, 1,
                                          with_differential ? &differential : nullptr);
              out.add_sample(local, radiance);
            }
          }
        }
      });
}

std::vector<TileRect> cut_tiles(int width, int height, int tile_size) {
  if (tile_size < 1) throw std::invalid_argument("tile size must be at least 1");
  std::vector<TileRect> tiles;
  for (int y = 0; y < height; y += tile_size)
    for (int x = 0; x < width; x += tile_size)
      tiles.push_back({x, y, std::min(x + tile_size, width), std::min(y + tile_size, height)});
  return tiles;
}

}  // namespace penumbra
