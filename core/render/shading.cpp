#include "core/render/shading.h"

#include "core/lights/light_geometry.h"

namespace penumbra {

SceneShading::SceneShading(std::shared_ptr<const PreparedScene> prepared, const MethodSpec& method)
    : prepared_(std::move(prepared)),
      scene_(&prepared_->scene()),
      direct_(*scene_, method),
      textures_(prepared_->textures()) {
  if (direct_.needs_line_query()) line_query_ = &prepared_->line_query();
}

SceneShading::SceneShading(std::shared_ptr<const Scene> scene, const MethodSpec& method)
    : SceneShading(std::make_shared<const PreparedScene>(std::move(scene)), method) {}

SceneShading::FirstHit SceneShading::first_hit(const Vec3& origin, const Vec3& direction,
                                               const RayDifferential* differential) const {
  FirstHit result;
  std::optional<SurfaceHit> hit = prepared_->embree().intersect(origin, direction);
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
  if (textures_ && is_pbrt_material(sp.material->type)) {
    SurfaceGeometry g = triangle_geometry(*scene_, hit->triangle, hit->barycentric);
    if (differential) set_footprint(g, *differential);
    result.surface = pbrt_surface_bsdf(*sp.material, g, *textures_);
  }
  result.shading_point = sp;
  if (textures_ && is_pbrt_material(sp.material->type))
    result.shading_point->bsdf = &result.surface;
  return result;
}

Rgb SceneShading::radiance(const Vec3& origin, const Vec3& direction, Pattern pattern,
                           const StreamKey& key, int sample_multiplier,
                           const RayDifferential* differential) const {
  return trace(origin, direction, 0, pattern, key, sample_multiplier, differential);
}

Rgb SceneShading::trace(const Vec3& origin, const Vec3& direction, int depth, Pattern pattern,
                        const StreamKey& key, int sample_multiplier,
                        const RayDifferential* differential) const {
  FirstHit hit = first_hit(origin, direction, differential);
  if (!hit.shading_point) return hit.emitted;
  const ShadingPoint& sp = *hit.shading_point;
  if (!sp.bsdf) return direct_.estimate(sp, *this, pattern, key, sample_multiplier);
  Rgb radiance;
  if (hit.surface.has_non_delta())
    radiance = direct_.estimate(sp, *this, pattern, key, sample_multiplier);
  // pbrt-v3's DirectLightingIntegrator: follow the delta lobes while depth + 1 < maxdepth and
  // light what they hit (the camera ray's hit is depth 0). Every branch is followed (pbrt-v3
  // picks one of several matching delta lobes at random: the same expectation).
  if (!hit.surface.has_delta() || depth + 1 >= scene_->max_depth) return radiance;
  SpecularBranch branches[SurfaceBsdf::kMaxLobes];
  int count = hit.surface.specular_branches(sp.wo, branches);
  for (int b = 0; b < count; ++b) {
    const Vec3& wi = branches[b].wi;
    // Leave the surface on wi's side of the geometric normal.
    Vec3 ng = hit.surface.geometric_normal();
    Vec3 offset = (dot(ng, wi) >= 0 ? ng : -ng) * prepared_->embree().ray_epsilon();
    // Each branch's shading point draws its own random numbers.
    StreamKey branch_key = key;
    branch_key.seed ^= 0x9e3779b97f4a7c15ull * uint64_t(1 + depth * SurfaceBsdf::kMaxLobes + b);
    // No footprint after a delta bounce: the chain's hit reads its textures at the finest MIP
    // level, the unfiltered value at the reflected point. Averaged over the pixel's samples that
    // converges to the texture over the reflected footprint, which filtering (pbrt-v3 carries
    // differentials through specular bounces) would approximate by a blur; the cost is noise at
    // few spp on finely detailed textures seen in mirrors and glass.
    Rgb incoming =
        trace(sp.position + offset, wi, depth + 1, pattern, branch_key, sample_multiplier, nullptr);
    radiance += branches[b].weight * incoming;
  }
  return is_finite(radiance) ? radiance : Rgb{};
}

}  // namespace penumbra
