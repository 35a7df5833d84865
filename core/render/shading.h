#pragma once
// Radiance along a camera ray: emitted radiance of a light seen directly, otherwise direct
// lighting at the first occluder hit with the method. Shared by the renderer and the probe.

#include <memory>
#include <optional>

#include "core/lines/line_query.h"
#include "core/materials/pbrt_shading.h"
#include "core/method/direct_lighting.h"
#include "core/render/embree_scene.h"
#include "core/render/prepared_scene.h"
#include "core/scene/scene.h"

namespace penumbra {

class SceneShading : public Visibility {
 public:
  // The method's estimator over a prepared scene shared with other methods (prepared_scene.h).
  // Throws FormatError for a method that cannot run on the scene.
  SceneShading(std::shared_ptr<const PreparedScene> prepared, const MethodSpec& method);
  // Prepares the scene for this shading alone.
  SceneShading(std::shared_ptr<const Scene> scene, const MethodSpec& method);

  const Scene& scene() const { return *scene_; }
  const PreparedScene& prepared() const { return *prepared_; }
  const EmbreeScene& embree() const { return prepared_->embree(); }
  const DirectLighting& direct_lighting() const { return direct_; }

  bool occluded(const Vec3& from, const Vec3& normal, const Vec3& to) const override {
    return prepared_->embree().occluded(from, normal, to);
  }
  // Only when the method has line terms (the shadow-triangle query over the occluders).
  const LineQuery* line_query() const override { return line_query_; }

  // What the camera ray sees first. Lights seen directly (front side) give `emitted`; an occluder
  // gives a shading point; nothing gives neither. A pbrt-v3 material's BSDF at the hit lives in
  // `surface` (the shading point points to it; copies re-point theirs).
  struct FirstHit {
    std::optional<ShadingPoint> shading_point;
    Rgb emitted;
    SurfaceBsdf surface;

    FirstHit() = default;
    FirstHit(const FirstHit& other) { *this = other; }
    FirstHit& operator=(const FirstHit& other) {
      shading_point = other.shading_point;
      emitted = other.emitted;
      surface = other.surface;
      if (shading_point && other.shading_point->bsdf == &other.surface)
        shading_point->bsdf = &surface;
      return *this;
    }
  };
  // `differential`: the camera ray's offset rays, for texture filtering (none: finest level).
  FirstHit first_hit(const Vec3& origin, const Vec3& direction,
                     const RayDifferential* differential = nullptr) const;

  Rgb radiance(const Vec3& origin, const Vec3& direction, Pattern pattern, const StreamKey& key,
               int sample_multiplier = 1, const RayDifferential* differential = nullptr) const;

  // Radiance along a ray that has followed `depth` delta lobes.
  Rgb trace(const Vec3& origin, const Vec3& direction, int depth, Pattern pattern,
            const StreamKey& key, int sample_multiplier, const RayDifferential* differential) const;

  // Does any material of the scene need texture footprints (image or checkerboard textures)?
  bool wants_differentials() const { return !scene_->textures.empty(); }

 private:
  std::shared_ptr<const PreparedScene> prepared_;
  const Scene* scene_;
  DirectLighting direct_;
  const LineQuery* line_query_ = nullptr;  // the prepared scene's, when the method needs it
  const SceneTextures* textures_;          // the prepared scene's, when some material is pbrt-v3's
};

}  // namespace penumbra
