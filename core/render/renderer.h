#pragma once
// The tile renderer: the unit of work of a worker and of a local render.
//
// A pass adds one sample per pixel (a jittered camera ray, then the method at the first hit).
// render_tile renders passes [pass_begin, pass_end) of a tile; results of different pass ranges
// merge exactly (core/render/tile.h), so a job split across workers is bit-identical to a local
// render with the same scene, method, sampler and seed.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/method/method.h"
#include "core/render/prepared_scene.h"
#include "core/render/tile.h"
#include "core/sampling/pattern.h"
#include "core/scene/scene.h"

namespace penumbra {

struct RenderOptions {
  std::string method = "sa";  // penumbra/method@1 text form
  Pattern sampler = Pattern::Stratified;
  uint64_t seed = 0;
};

class Renderer {
 public:
  // Builds the Embree scene and the line-query BVH. Throws FormatError for a method that cannot
  // run on this scene (unknown strategy, strategy not available yet, method/material mismatch).
  Renderer(std::shared_ptr<const Scene> scene, const RenderOptions& options);
  // Over a prepared scene shared with other renderers (other methods, samplers, seeds): only
  // the method's estimator is built here.
  Renderer(std::shared_ptr<const PreparedScene> prepared, const RenderOptions& options);
  // The same with options.method already parsed into `method` (its text stays in the options for
  // the image's metadata): a worker parses each task's method once, where it decodes the task.
  Renderer(std::shared_ptr<const PreparedScene> prepared, const RenderOptions& options,
           const MethodSpec& method);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  const Scene& scene() const;
  const RenderOptions& options() const;

  // Renders passes [pass_begin, pass_end) of `tile` into `out` (which must have tile's rect),
  // in parallel with TBB in the calling thread's task arena (limit threads with a
  // tbb::task_arena around the call).
  void render_tile(const TileRect& tile, uint32_t pass_begin, uint32_t pass_end,
                   TileAccumulator& out) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Cuts a width x height image into tiles of at most tile_size x tile_size, row-major.
std::vector<TileRect> cut_tiles(int width, int height, int tile_size);

}  // namespace penumbra
