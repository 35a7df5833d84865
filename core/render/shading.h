#pragma once
// Radiance along a camera ray: emitted radiance of a light seen directly, otherwise direct
// lighting at the first occluder hit with the method. Shared by the renderer and the probe.

#include <memory>
#include <optional>

#include "core/lines/line_query.h"
#include "core/method/direct_lighting.h"
#include "core/render/embree_scene.h"
#include "core/scene/scene.h"

namespace penumbra {

class SceneShading : public Visibility {
 public:
  SceneShading(std::shared_ptr<const Scene> scene, const MethodSpec& method);

  const Scene& scene() const { return *scene_; }
  const EmbreeScene& embree() const { return embree_; }
  const DirectLighting& direct_lighting() const { return direct_; }

  bool occluded(const Vec3& from, const Vec3& normal, const Vec3& to) const override {
    return embree_.occluded(from, normal, to);
  }
  // Built only when the method has line terms (the shadow-triangle query over the occluders).
  const LineQuery* line_query() const override { return line_query_.get(); }

  // What the camera ray sees first. Lights seen directly (front side) give `emitted`; an occluder
  // gives a shading point; nothing gives neither.
  struct FirstHit {
    std::optional<ShadingPoint> shading_point;
    Rgb emitted;
  };
  FirstHit first_hit(const Vec3& origin, const Vec3& direction) const;

  Rgb radiance(const Vec3& origin, const Vec3& direction, Pattern pattern, const StreamKey& key,
               int sample_multiplier = 1) const;

 private:
  std::shared_ptr<const Scene> scene_;
  EmbreeScene embree_;
  DirectLighting direct_;
  std::unique_ptr<LineQuery> line_query_;
};

}  // namespace penumbra
