// The peer scenes (pbrt-v3 files of Salesin & Jarosz's implementation) read as the seed system
// reads them: triangle counts, lights and their emitting sides, cameras, and the integrator
// settings mapped onto methods. Skipped when ../shared/peer-scenes is not on this machine.

#include "tests/support/peer_scenes.h"

#include <gtest/gtest.h>

#include "core/scene/scene.h"

namespace penumbra {
namespace {

TEST(PeerScenes, KitchenGeometryCameraLightAndSettings) {
  const std::string path = testing::peer_scene("kitchen/kitchen-play.pbrt");
  if (path.empty()) GTEST_SKIP() << testing::peer_scene_missing("kitchen/kitchen-play.pbrt");
  Scene scene = load_scene(path);
  // 294 PLY meshes and a few inline ones; zero-area triangles dropped.
  EXPECT_EQ(scene.triangle_count(), 1414684u);
  EXPECT_EQ(scene.normals.size(), scene.positions.size());
  EXPECT_EQ(scene.uvs.size(), scene.positions.size());
  EXPECT_EQ(scene.textures.size(), 20u);
  EXPECT_EQ(scene.max_depth, 1);
  // The window: the seed's quad o, u, v, emitting along cross(u, v) = +z into the room.
  ASSERT_EQ(scene.lights.size(), 1u);
  const Light& window = scene.lights[0];
  EXPECT_EQ(window.type, LightType::Quad);
  EXPECT_EQ(window.origin, Vec3(-0.75145, 0.873153, -3.1173));
  EXPECT_EQ(window.edge1, Vec3(1.623528, 0, 0));
  EXPECT_EQ(window.edge2, Vec3(0, 2.201277, 0));
  EXPECT_EQ(window.normal, Vec3(0, 0, 1));
  EXPECT_EQ(window.radiance, Rgb(40, 40, 40));
  // Camera: the inverse of the file's world-to-camera matrix (a rotation R and translation t,
  // column-major): the eye is -R^T t.
  const double r[3][3] = {{0.89874, 1.86265e-009, -0.438481},
                          {-0.0182716, 0.999132, -0.0374507},
                          {-0.4381, -0.0416703, -0.89796}};
  const double t[3] = {0.600822, -1.63678, 4.06504};
  for (int axis = 0; axis < 3; ++axis) {
    double eye = -(r[0][axis] * t[0] + r[1][axis] * t[1] + r[2][axis] * t[2]);
    EXPECT_NEAR(scene.camera.position[axis], eye, 1e-5);
    // The view direction is the camera's +z: R's third row.
    EXPECT_NEAR(normalize(scene.camera.look_at - scene.camera.position)[axis], r[2][axis], 1e-5);
  }
  EXPECT_FALSE(scene.camera.mirror_x);
  EXPECT_EQ(scene.camera.width, 1280);
  EXPECT_EQ(scene.camera.height, 720);
  EXPECT_DOUBLE_EQ(scene.camera.fov_y_deg, 35.983398);
  EXPECT_EQ(scene.camera.filter.radius_x, 1.0);
  // brdf + vertical solid-angle lines, 2x2 light samples split by stratification.
  EXPECT_EQ(scene.render_defaults.method, "2*bsdf+2*line-sa:v/balance");
  EXPECT_EQ(scene.render_defaults.sampler, "stratified");
  EXPECT_EQ(scene.render_defaults.spp, 4u);
}

TEST(PeerScenes, VeachLightsFaceThePlates) {
  const std::string path = testing::peer_scene("op-veach/op-veach-color.pbrt");
  if (path.empty()) GTEST_SKIP() << testing::peer_scene_missing("op-veach/op-veach-color.pbrt");
  Scene scene = load_scene(path);
  EXPECT_EQ(scene.triangle_count(), 16u);  // 4 plates, 4 occluders
  ASSERT_EQ(scene.lights.size(), 4u);
  for (const Light& light : scene.lights) {
    // "Scale -1 1 1" swaps handedness, which flips the seed's quads: they face down towards the
    // plates (-y) and forwards (+z), not up.
    EXPECT_LT(light.normal.y, -0.8);
    EXPECT_GT(light.normal.z, 0.4);
  }
  EXPECT_EQ(scene.render_defaults.method, "bsdf+line-sa:v/balance");
  EXPECT_EQ(scene.render_defaults.sampler, "random");
  EXPECT_EQ(scene.render_defaults.spp, 1u);
  EXPECT_TRUE(scene.camera.mirror_x);  // pbrt's LookAt camera
}

}  // namespace
}  // namespace penumbra
