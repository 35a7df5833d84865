#pragma once
// A scene made ready to render: its Embree BVH, its textures and, for methods with line terms,
// its line-query BVH (built on first use). It depends on the scene alone, not on the method, so
// every Renderer of the scene shares one (a worker keys them by the scene's content hash); what
// a method adds (its direct-lighting estimator, core/method/direct_lighting.h) is small.

#include <atomic>
#include <cstddef>
#include <memory>
#include <mutex>

#include "core/lines/line_query.h"
#include "core/materials/pbrt_shading.h"
#include "core/render/embree_scene.h"
#include "core/scene/scene.h"

namespace penumbra {

class PreparedScene {
 public:
  // Builds the Embree scene and the textures. Throws FormatError for a pbrt-v3 material the
  // shading cannot model, or a texture image that cannot be decoded.
  explicit PreparedScene(std::shared_ptr<const Scene> scene);
  PreparedScene(const PreparedScene&) = delete;
  PreparedScene& operator=(const PreparedScene&) = delete;

  const Scene& scene() const { return *scene_; }
  const std::shared_ptr<const Scene>& shared_scene() const { return scene_; }
  const EmbreeScene& embree() const { return embree_; }
  // The pbrt-v3 materials' textures; null when no material is a pbrt-v3 one.
  const SceneTextures* textures() const { return textures_.get(); }
  // The line-query BVH over the occluders: built by the first caller (others wait), then shared.
  const LineQuery& line_query() const;

  // What it holds, approximately: the scene's arrays and texture files, the Embree BVH (as
  // Embree reports its allocations) and the line-query BVH once built. For bounding caches.
  size_t memory_bytes() const;

 private:
  std::shared_ptr<const Scene> scene_;
  EmbreeScene embree_;
  std::unique_ptr<SceneTextures> textures_;
  mutable std::once_flag line_query_once_;
  mutable std::unique_ptr<LineQuery> line_query_;
  mutable std::atomic<size_t> line_query_bytes_{0};
  size_t scene_bytes_ = 0;
};

}  // namespace penumbra
