#include "core/render/shading.h"

#include "core/lights/light_geometry.h"

namespace penumbra {

SceneShading::SceneShading(std::shared_ptr<const Scene> scene, const MethodSpec& method)
    : scene_(std::move(scene)), embree_(*scene_), direct_(*scene_, method) {
  if (direct_.needs_line_query()) line_query_ = std::make_unique<LineQuery>(*scene_);
}

SceneShading::FirstHit SceneShading::first_hit(const Vec3& origin, const Vec3& direction) const {
  FirstHit result;
  std::optional<SurfaceHit> hit = embree_.intersect(origin, direction);
  double nearest = hit ? hit->distance : 1e300;

  // Lights are not in the Embree scene: test them analytically.
  const Light* seen_light = nullptr;
  Vec3 light_point;
  for (const Light& light : scene_->lights) {
    std::optional<LightHit> light_hit = intersect_light(light, origin, direction, 0.0, nearest);
    if (light_hit && light_hit->distance < nearest) {
      nearest = light_hit->distance;
      seen_light = &light;
      light_point = light_hit->point;
    }
  }
  if (seen_light) {
    result.emitted = emitted_radiance(*seen_light, light_point, -direction);
    return result;
  }
  if (!hit) return result;

  ShadingPoint sp;
  sp.position = hit->position;
  sp.wo = -direction;
  sp.normal =
      dot(hit->geometric_normal, sp.wo) < 0 ? -hit->geometric_normal : hit->geometric_normal;
  sp.material = &scene_->materials[scene_->triangle_materials[hit->triangle]];
  result.shading_point = sp;
  return result;
}

Rgb SceneShading::radiance(const Vec3& origin, const Vec3& direction, Pattern pattern,
                           const StreamKey& key, int sample_multiplier) const {
  FirstHit hit = first_hit(origin, direction);
  if (!hit.shading_point) return hit.emitted;
  return direct_.estimate(*hit.shading_point, *this, pattern, key, sample_multiplier);
}

}  // namespace penumbra
