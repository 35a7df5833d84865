#pragma once
// What every scene the reader accepts must satisfy (scene.h, SCENE_FORMAT.md), checked by the
// scene-reading fuzz targets after each successful parse.

#include <cmath>

#include "core/scene/scene.h"
#include "fuzz/fuzz_check.h"

namespace penumbra::fuzz {

inline void check_scene_invariants(const Scene& scene, const SceneLimits& limits) {
  FUZZ_CHECK(scene.content_hash.size() == 64);
  const Camera& camera = scene.camera;
  FUZZ_CHECK(camera.width >= 1 && camera.width <= limits.max_resolution);
  FUZZ_CHECK(camera.height >= 1 && camera.height <= limits.max_resolution);
  FUZZ_CHECK(camera.fov_y_deg > 0 && camera.fov_y_deg < 180);
  FUZZ_CHECK(is_finite(camera.position) && is_finite(camera.look_at) && is_finite(camera.up));
  FUZZ_CHECK(!scene.materials.empty() || scene.triangle_count() == 0);
  FUZZ_CHECK(scene.indices.size() % 3 == 0);
  FUZZ_CHECK(scene.triangle_materials.size() == scene.triangle_count());
  FUZZ_CHECK(scene.triangle_count() <= limits.max_triangles);
  for (uint32_t index : scene.indices) FUZZ_CHECK(index < scene.positions.size());
  for (uint32_t material : scene.triangle_materials) FUZZ_CHECK(material < scene.materials.size());
  for (const Vec3& p : scene.positions) {
    FUZZ_CHECK(is_finite(p));
    for (int axis = 0; axis < 3; ++axis) FUZZ_CHECK(std::abs(p[axis]) <= limits.max_coordinate);
  }
  FUZZ_CHECK(!scene.lights.empty() && scene.lights.size() <= limits.max_lights);
  for (const Light& light : scene.lights) {
    FUZZ_CHECK(std::isfinite(light.area) && light.area > 0);
    FUZZ_CHECK(is_finite(light.normal) && std::abs(length(light.normal) - 1) < 1e-9);
    FUZZ_CHECK(is_finite(light.centroid));
    FUZZ_CHECK(light.radiance.x >= 0 && light.radiance.y >= 0 && light.radiance.z >= 0);
    FUZZ_CHECK(is_finite(light.radiance));
  }
  for (const auto& [name, region] : scene.regions) {
    FUZZ_CHECK(region.x0 >= 0 && region.y0 >= 0 && region.x0 < region.x1 && region.y0 < region.y1);
    FUZZ_CHECK(region.x1 <= camera.width && region.y1 <= camera.height);
  }
}

// Small limits keep each run fast; the checks behind them are the same code at any size.
inline SceneLimits fuzz_scene_limits() {
  SceneLimits limits;
  limits.max_triangles = 50'000;
  limits.max_sphere_subdivisions = 4;
  limits.max_json_bytes = size_t{1} << 20;
  limits.max_file_bytes = size_t{1} << 20;
  return limits;
}

}  // namespace penumbra::fuzz
