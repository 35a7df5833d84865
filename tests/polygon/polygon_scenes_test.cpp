// The four bundled scenes of Peters 2021's experiments (scenes/polygon-cornell.json,
// occluded-planes.json, distant-light.json, pentagon-room.json): they load, have the geometry
// their figure needs and regions inside the image, and render finite images with every polygon
// method (sa, psa, ltc, their MIS combinations and Peters' weighted / clamped-optimal).

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <memory>

#include "core/render/local_render.h"
#include "core/render/renderer.h"
#include "core/scene/scene.h"

namespace penumbra {
namespace {

const std::filesystem::path kScenes = std::filesystem::path(PENUMBRA_SOURCE_DIR) / "scenes";
constexpr const char* kPolygonScenes[] = {"polygon-cornell", "occluded-planes", "distant-light",
                                          "pentagon-room"};

Scene load(const std::string& name) {
  return load_scene((kScenes / (name + ".json")).string());
}

TEST(PolygonScenes, LoadWithRegionsInsideTheImage) {
  for (const char* name : kPolygonScenes) {
    SCOPED_TRACE(name);
    Scene scene = load(name);
    EXPECT_EQ(scene.name, name);
    EXPECT_TRUE(scene.warnings.empty());
    EXPECT_EQ(scene.camera.width, 512);
    EXPECT_EQ(scene.camera.height, 512);
    EXPECT_GE(scene.regions.size(), 2u);
    for (const auto& [region_name, r] : scene.regions) {
      EXPECT_GE((r.x1 - r.x0) * (r.y1 - r.y0), 32) << region_name;
      EXPECT_GE(r.x0, 0);
      EXPECT_GE(r.y0, 0);
      EXPECT_LE(r.x1, scene.camera.width);
      EXPECT_LE(r.y1, scene.camera.height);
    }
    for (const Light& light : scene.lights) EXPECT_NE(light.type, LightType::Disk);
  }
}

TEST(PolygonScenes, HaveTheGeometryOfTheirFigures) {
  {
    // Fig. 12: a rectangle through the box (beyond both side walls at x = +-1), its edges along
    // the walls' normals (x and z).
    Scene scene = load("polygon-cornell");
    ASSERT_EQ(scene.lights.size(), 1u);
    const Light& light = scene.lights[0];
    EXPECT_EQ(light.type, LightType::Quad);
    EXPECT_LT(light.origin.x, -1.0);
    EXPECT_GT(light.origin.x + light.edge1.x, 1.0);
    EXPECT_EQ(light.edge1.y, 0.0);
    EXPECT_EQ(light.edge1.z, 0.0);
    EXPECT_EQ(light.edge2.x, 0.0);
    EXPECT_EQ(light.edge2.y, 0.0);
  }
  {
    // Fig. 7: a 1 cm and a 1 mm square, 40 m from the wall at z = 0.
    Scene scene = load("distant-light");
    ASSERT_EQ(scene.lights.size(), 2u);
    EXPECT_NEAR(length(scene.lights[0].edge1), 0.01, 1e-12);
    EXPECT_NEAR(length(scene.lights[1].edge1), 0.001, 1e-12);
    for (const Light& light : scene.lights) EXPECT_NEAR(light.centroid.z, 40.0, 1e-9);
  }
  {
    Scene scene = load("pentagon-room");
    ASSERT_EQ(scene.lights.size(), 1u);
    EXPECT_EQ(scene.lights[0].type, LightType::Polygon);
    EXPECT_EQ(scene.lights[0].vertices.size(), 5u);
    EXPECT_LT(scene.lights[0].normal.y, -0.99);
  }
  {
    Scene scene = load("occluded-planes");
    ASSERT_EQ(scene.lights.size(), 1u);
    bool diffuse_blue = false, glossy_white = false;
    for (const Material& m : scene.materials) {
      diffuse_blue |= m.diffuse.z > 0.5 && m.diffuse.x < 0.1;
      glossy_white |= m.type == MaterialType::Ggx && m.specular.x > 0.5 && m.roughness < 0.3;
    }
    EXPECT_TRUE(diffuse_blue);
    EXPECT_TRUE(glossy_white);
  }
}

TEST(PolygonScenes, RenderFiniteImagesWithEveryPolygonMethod) {
  for (const char* name : kPolygonScenes) {
    auto scene = std::make_shared<Scene>(load(name));
    // A small image of the same view.
    scene->camera.width = scene->camera.height = 40;
    for (const char* method :
         {"area", "sa", "psa", "ltc", "bsdf+sa", "bsdf+psa", "psa+ltc", "psa+ltc/weighted",
          "psa+ltc/clamped-optimal", "2*psa+ltc/clamped-optimal"}) {
      SCOPED_TRACE(std::string(name) + " " + method);
      Renderer renderer(scene, RenderOptions{method, Pattern::Stratified, 7});
      RenderBudget budget;
      budget.spp = 2;
      LocalRenderResult r = render_local(renderer, budget, 2, 20);
      EXPECT_EQ(r.film.nonfinite_samples, 0u);
      double sum = 0;
      for (float v : r.film.color.rgb) {
        ASSERT_TRUE(std::isfinite(v));
        ASSERT_GE(v, 0.0f);
        sum += v;
      }
      EXPECT_GT(sum, 0.0);  // the light reaches something
    }
  }
}

}  // namespace
}  // namespace penumbra
