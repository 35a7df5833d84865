// Specular chains (pbrt-v3's DirectLightingIntegrator): a mirror shows what it reflects times Kr
// while depth + 1 < maxdepth, and nothing beyond. Closed form: a Lambert floor under a quad light
// with nothing in between reflects albedo * Le * F (Lambert's polygon formula), and psa
// (projected solid angle sampling) is exact there, so every value is deterministic.

#include <gtest/gtest.h>

#include <memory>

#include "core/math/lambert_polygon.h"
#include "core/render/shading.h"
#include "core/scene/light_setup.h"

namespace penumbra {
namespace {

std::shared_ptr<Scene> mirror_scene(int max_depth) {
  auto s = std::make_shared<Scene>();
  Material floor;
  floor.name = "floor";
  floor.type = MaterialType::Lambert;
  floor.albedo = {0.5, 0.4, 0.3};
  Material mirror = pbrt_material_defaults(MaterialType::Mirror);
  mirror.name = "mirror";
  s->materials = {floor, mirror};
  // Floor z = 0 (normal +z), mirror x = 1 facing -x (z in [0.5, 2]).
  s->positions = {{-3, -3, 0},  {3, -3, 0},  {3, 3, 0}, {-3, 3, 0},
                  {1, -3, 0.5}, {1, 3, 0.5}, {1, 3, 2}, {1, -3, 2}};
  s->indices = {0, 1, 2, 0, 2, 3, 4, 5, 6, 4, 6, 7};
  s->triangle_materials = {0, 0, 1, 1};
  // A downward-facing quad light at z = 2 over the origin.
  s->lights.push_back(make_quad_light({-0.5, 0.5, 2}, {1, 0, 0}, {0, -1, 0}, {3, 3, 3}));
  s->max_depth = max_depth;
  return s;
}

TEST(SpecularChain, MirrorShowsTheFloorTimesKrWithinMaxDepth) {
  const Vec3 floor_point{-0.8, 0, 0};
  auto reference = mirror_scene(5);
  const Light& light = reference->lights[0];
  Rgb expected_floor =
      lambert_polygon_radiance(reference->materials[0].albedo, light.radiance, floor_point,
                               {0, 0, 1}, light.vertices, light.normal);
  ASSERT_GT(expected_floor.x, 0.01);
  // A camera ray at (0.8, 0, 1) towards (1, 0, 0.9) on the mirror reflects onto floor_point.
  const Vec3 origin{0.8, 0, 1};
  const Vec3 direction = normalize(Vec3{0.2, 0, -0.1});
  MethodSpec psa = parse_method("psa");
  StreamKey key{1, 0, 0, 0};
  for (int max_depth : {1, 2, 5}) {
    SceneShading shading(mirror_scene(max_depth), psa);
    // The floor itself, straight down: depth 0, lit whatever the max depth.
    Rgb direct = shading.radiance({-0.8, 0, 1}, {0, 0, -1}, Pattern::Random, key);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(direct[c], expected_floor[c], 1e-6 * expected_floor[c]);
    Rgb via_mirror = shading.radiance(origin, direction, Pattern::Random, key);
    double kr = 0.9;  // pbrt-v3's default mirror Kr
    for (int c = 0; c < 3; ++c) {
      if (max_depth == 1)
        EXPECT_EQ(via_mirror[c], 0.0) << "maxdepth 1 lights the camera ray's hit only";
      else
        // The reflected ray leaves the mirror offset by the ray epsilon (1e-4 of the scene): its
        // floor point moves by ~2e-4, which changes the form factor by ~4e-5 relative.
        EXPECT_NEAR(via_mirror[c], kr * expected_floor[c], 2e-4 * expected_floor[c])
            << "max depth " << max_depth;
    }
  }
}

}  // namespace
}  // namespace penumbra
