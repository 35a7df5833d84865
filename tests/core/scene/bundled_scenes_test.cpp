// Every bundled scene under scenes/ (those of other experiments too) loads cleanly and says which
// paper figure it mirrors; the five scenes of the scene brief keep the properties their
// experiments need; cornell-box.json is the peer scene, value for value.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/scene/scene.h"
#include "tests/support/peer_scenes.h"

namespace penumbra {
namespace {

const std::filesystem::path kScenes = std::filesystem::path(PENUMBRA_SOURCE_DIR) / "scenes";

Scene load_bundled(const std::string& name) {
  return load_scene((kScenes / name).string());
}

std::vector<std::filesystem::path> bundled_scene_files() {
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(kScenes))
    if (entry.path().extension() == ".json") files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  return files;
}

TEST(BundledScenes, TheFiveExperimentsArePresentWithRegions) {
  for (const char* name : {"cornell-box.json", "cornell-occluders.json", "quad-over-floor.json",
                           "spheres-plane-square.json", "spheres-plane-disk.json"}) {
    SCOPED_TRACE(name);
    ASSERT_TRUE(std::filesystem::exists(kScenes / name));
    // Square 256 or 512 images, lights facing down, and (each mirrors a figure with crops) at
    // least two named regions of at least 32 pixels.
    Scene scene = load_bundled(name);
    EXPECT_TRUE(scene.camera.width == 256 || scene.camera.width == 512);
    EXPECT_EQ(scene.camera.width, scene.camera.height);
    for (const Light& light : scene.lights) EXPECT_LT(light.normal.y, -0.99);  // facing down
    EXPECT_GE(scene.regions.size(), 2u);
    for (const auto& [region_name, region] : scene.regions)
      EXPECT_GE((region.x1 - region.x0) * (region.y1 - region.y0), 32) << region_name;
  }
}

TEST(BundledScenes, EveryOneLoadsCleanly) {
  auto files = bundled_scene_files();
  ASSERT_GE(files.size(), 5u);
  for (const auto& file : files) {
    SCOPED_TRACE(file.string());
    Scene scene = load_scene(file.string());
    EXPECT_EQ(scene.name, file.stem().string());
    EXPECT_FALSE(scene.description.empty());
    EXPECT_TRUE(scene.warnings.empty()) << scene.warnings.front();
    EXPECT_GT(scene.triangle_count(), 0u);
    EXPECT_FALSE(scene.lights.empty());
    // Every triangle has positive area.
    for (size_t t = 0; t < scene.triangle_count(); ++t) {
      const Vec3& a = scene.positions[scene.indices[3 * t]];
      const Vec3& b = scene.positions[scene.indices[3 * t + 1]];
      const Vec3& c = scene.positions[scene.indices[3 * t + 2]];
      EXPECT_GT(length(cross(b - a, c - a)), 0);
    }
  }
}

TEST(BundledScenes, CornellBoxIsThePeerScene) {
  Scene scene = load_bundled("cornell-box.json");
  // Camera: pbrt's transform puts the eye at (0, 1, 6.8) looking down -z; fov 19.5 (square).
  EXPECT_EQ(scene.camera.position, Vec3(0, 1, 6.8));
  Vec3 view = normalize(scene.camera.look_at - scene.camera.position);
  EXPECT_EQ(view, Vec3(0, 0, -1));
  EXPECT_EQ(scene.camera.up, Vec3(0, 1, 0));
  EXPECT_EQ(scene.camera.fov_y_deg, 19.5);
  EXPECT_EQ(scene.camera.width, 512);
  EXPECT_EQ(scene.camera.height, 512);
  // Light: pbrt quad o, u, v and L.
  ASSERT_EQ(scene.lights.size(), 1u);
  const Light& light = scene.lights[0];
  EXPECT_EQ(light.type, LightType::Quad);
  EXPECT_EQ(light.origin, Vec3(-0.24, 1.98, -0.22));
  EXPECT_EQ(light.edge1, Vec3(0.47, 0, 0));
  EXPECT_EQ(light.edge2, Vec3(0, 0, 0.38));
  EXPECT_EQ(light.radiance, Rgb(68, 48, 16));
  // 5 walls of 2 triangles and 2 boxes of 12, all lambert (pbrt's matte).
  EXPECT_EQ(scene.triangle_count(), 34u);
  for (const Material& m : scene.materials) EXPECT_EQ(m.type, MaterialType::Lambert);
}

// The peer scene file, when present on this machine, against the bundled JSON: every mesh's
// points and indices and every matte Kd, value for value.
// The text between the brackets that follow `key` after position `from` of a pbrt file.
std::string bracketed_after(const std::string& text, size_t from, const std::string& key) {
  size_t open = text.find('[', text.find(key, from));
  return text.substr(open + 1, text.find(']', open) - open - 1);
}

TEST(BundledScenes, CornellBoxMatchesThePbrtFileValueForValue) {
  const std::string pbrt_path = testing::peer_scene("cornell-box/cornell-box.pbrt");
  if (pbrt_path.empty())
    GTEST_SKIP() << testing::peer_scene_missing("cornell-box/cornell-box.pbrt");
  std::ifstream in(pbrt_path);
  ASSERT_TRUE(in) << pbrt_path;
  std::stringstream text;
  text << in.rdbuf();
  std::string pbrt = text.str();
  auto numbers = [](const std::string& list) {
    std::vector<double> out;
    std::istringstream stream(list);
    for (double x; stream >> x;) out.push_back(x);
    return out;
  };

  Scene scene = load_bundled("cornell-box.json");
  size_t triangle = 0;
  int meshes = 0;
  for (size_t at = pbrt.find("Shape \"trianglemesh\""); at != std::string::npos;
       at = pbrt.find("Shape \"trianglemesh\"", at + 1)) {
    ++meshes;
    std::vector<double> indices = numbers(bracketed_after(pbrt, at, "\"integer indices\""));
    std::vector<double> points = numbers(bracketed_after(pbrt, at, "\"point P\""));
    ASSERT_LE(triangle + indices.size() / 3, scene.triangle_count());
    for (size_t k = 0; k < indices.size(); ++k) {
      size_t i = static_cast<size_t>(indices[k]);
      Vec3 expected{points[3 * i], points[3 * i + 1], points[3 * i + 2]};
      EXPECT_EQ(scene.positions[scene.indices[3 * triangle + k]], expected);
    }
    triangle += indices.size() / 3;
  }
  EXPECT_EQ(meshes, 7);
  EXPECT_EQ(triangle, scene.triangle_count());

  int materials = 0;
  const std::string make = "MakeNamedMaterial \"";
  for (size_t at = pbrt.find(make); at != std::string::npos; at = pbrt.find(make, at + 1)) {
    size_t name_begin = at + make.size();
    std::string name = pbrt.substr(name_begin, pbrt.find('"', name_begin) - name_begin);
    if (name == "Light") continue;  // the emitter's black matte: lights do not occlude here
    ++materials;
    std::vector<double> kd = numbers(bracketed_after(pbrt, at, "\"rgb Kd\""));
    ASSERT_EQ(kd.size(), 3u) << name;
    bool found = false;
    for (const Material& m : scene.materials) found |= m.albedo == Rgb(kd[0], kd[1], kd[2]);
    EXPECT_TRUE(found) << name;
  }
  EXPECT_EQ(materials, 7);
}

TEST(BundledScenes, CornellOccludersHasFloatingOccludersAndGlossyMaterials) {
  Scene scene = load_bundled("cornell-occluders.json");
  bool has_glossy = false;
  for (const Material& m : scene.materials) has_glossy |= m.type != MaterialType::Lambert;
  EXPECT_TRUE(has_glossy);
  // Occluders float between the floor and the light: count triangles entirely in 0.3 < y < 1.9.
  size_t floating = 0;
  for (size_t t = 0; t < scene.triangle_count(); ++t) {
    bool inside = true;
    for (int k = 0; k < 3; ++k) {
      double y = scene.positions[scene.indices[3 * t + k]].y;
      inside &= y > 0.3 && y < 1.9;
    }
    floating += inside;
  }
  EXPECT_GE(floating, 50u);
  EXPECT_TRUE(scene.regions.count("penumbra"));
  EXPECT_TRUE(scene.regions.count("glossy"));
}

TEST(BundledScenes, QuadOverFloorAlignsOccluderWithLightEdges) {
  Scene scene = load_bundled("quad-over-floor.json");
  ASSERT_EQ(scene.lights.size(), 1u);
  const Light& light = scene.lights[0];
  // Perpendicular edges, so both line directions (u, v) and Ureña's `sa` apply.
  EXPECT_EQ(dot(light.edge1, light.edge2), 0);
  EXPECT_TRUE(scene.regions.count("penumbra-edge1"));
  EXPECT_TRUE(scene.regions.count("penumbra-edge2"));
}

TEST(BundledScenes, SpheresPlaneSquareAndDiskDifferOnlyInTheLight) {
  Scene square = load_bundled("spheres-plane-square.json");
  Scene disk = load_bundled("spheres-plane-disk.json");
  EXPECT_EQ(square.positions, disk.positions);
  EXPECT_EQ(square.indices, disk.indices);
  ASSERT_EQ(square.lights.size(), 1u);
  ASSERT_EQ(disk.lights.size(), 1u);
  EXPECT_EQ(square.lights[0].type, LightType::Quad);
  EXPECT_EQ(disk.lights[0].type, LightType::Disk);
  EXPECT_NEAR(square.lights[0].area, disk.lights[0].area, 1e-12 * square.lights[0].area);
  EXPECT_EQ(square.lights[0].centroid, disk.lights[0].centroid);
  EXPECT_EQ(square.lights[0].radiance, disk.lights[0].radiance);
  EXPECT_EQ(square.regions.size(), disk.regions.size());
}

}  // namespace
}  // namespace penumbra
