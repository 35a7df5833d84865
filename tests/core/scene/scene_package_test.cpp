// Scene packages and content hashes: the file route and the package route agree (scene and
// hash), the hash is stable and follows every byte of the JSON and the OBJ files, packages never
// touch the filesystem, and OBJ paths cannot leave the scene's folder (symlinks included).

#include "core/scene/scene_package.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <stdexcept>

#include "core/scene/scene.h"
#include "core/scene/scene_path.h"
#include "scene_test_support.h"

namespace penumbra {
namespace {

using testing::TempDir;

constexpr const char* kTwoObjScene = R"json({
  "format": "penumbra/scene@1",
  "camera": { "position": [0,1,3.5], "look_at": [0,1,0], "fov_y_deg": 40, "width": 64, "height": 64 },
  "materials": { "white": { "type": "lambert", "albedo": [0.8,0.8,0.8] } },
  "shapes": [
    { "type": "obj", "file": "meshes/a.obj", "material": "white" },
    { "type": "obj", "file": "b.obj", "scale": 2, "material": "white" },
    { "type": "obj", "file": "./meshes/a.obj", "translate": [1,0,0], "material": "white" }
  ],
  "lights": [ { "type": "quad", "origin": [-0.25,1.98,-0.25], "edge1": [0.5,0,0], "edge2": [0,0,0.5],
                "radiance": [10,10,10] } ]
})json";

class TwoObjScene : public ::testing::Test {
 protected:
  void SetUp() override {
    scene_path_ = folder_.write("scene.json", kTwoObjScene);
    folder_.write("meshes/a.obj", testing::tetrahedron_obj());
    folder_.write("b.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  }
  TempDir folder_;
  std::string scene_path_;
};

TEST_F(TwoObjScene, PackageHoldsTheJsonAndEachObjOnce) {
  ScenePackage package = collect_scene_package(scene_path_);
  EXPECT_EQ(package.scene_json, kTwoObjScene);
  ASSERT_EQ(package.files.size(), 2u);  // meshes/a.obj appears twice, under two spellings
  EXPECT_EQ(package.files.at("meshes/a.obj"), testing::tetrahedron_obj());
  EXPECT_TRUE(package.files.count("b.obj"));
}

TEST_F(TwoObjScene, PackageRouteEqualsFileRoute) {
  Scene from_file = load_scene(scene_path_);
  ScenePackage package = collect_scene_package(scene_path_);
  // Move the files away: the package route must not need them.
  std::filesystem::remove_all(folder_.path() / "meshes");
  std::filesystem::remove(folder_.path() / "b.obj");
  Scene from_package = parse_scene_package(package);
  EXPECT_EQ(from_package.content_hash, from_file.content_hash);
  EXPECT_EQ(from_package.positions, from_file.positions);
  EXPECT_EQ(from_package.indices, from_file.indices);
  EXPECT_EQ(from_package.triangle_materials, from_file.triangle_materials);
  EXPECT_EQ(from_file.triangle_count(), 4u + 1u + 4u);
  // The same hash from the documented canonical form.
  EXPECT_EQ(from_file.content_hash,
            scene_content_hash(kTwoObjScene, {{"meshes/a.obj", testing::tetrahedron_obj()},
                                              {"b.obj", package.files.at("b.obj")}}));
}

TEST_F(TwoObjScene, HashIsStableAndFollowsEveryByte) {
  const std::string first = load_scene(scene_path_).content_hash;
  EXPECT_EQ(first.size(), 64u);
  EXPECT_EQ(load_scene(scene_path_).content_hash, first);  // deterministic

  // One changed byte in an OBJ file (a comment: the geometry is unchanged) changes the hash.
  folder_.write("b.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n#");
  const std::string after_obj_change = load_scene(scene_path_).content_hash;
  EXPECT_NE(after_obj_change, first);

  // One changed byte of JSON whitespace changes it too.
  folder_.write("scene.json", std::string(kTwoObjScene) + " ");
  EXPECT_NE(load_scene(scene_path_).content_hash, after_obj_change);
}

TEST(ContentHash, KnownValueAndFraming) {
  // SHA-256 of 8 zero bytes (the length of the empty JSON text) followed by nothing.
  EXPECT_EQ(scene_content_hash("", {}),
            "af5570f5a1810b7af78caf4bc70a660f0df51e42baf91d4de5b2328de0e83dfc");
  // Moving a byte between a path and the file bytes changes the hash (length framing).
  EXPECT_NE(scene_content_hash("{}", {{"a.obj", "xv"}}),
            scene_content_hash("{}", {{"a.objx", "v"}}));
  EXPECT_NE(scene_content_hash("{}", {{"a.obj", ""}}), scene_content_hash("{}", {}));
}

TEST_F(TwoObjScene, PackageMissingAFileIsRefused) {
  ScenePackage package = collect_scene_package(scene_path_);
  package.files.erase("b.obj");
  try {
    parse_scene_package(package);
    FAIL() << "parsed a package without one of its files";
  } catch (const FormatError& error) {
    EXPECT_EQ(error.json_path(), "$.shapes[1].file");
    EXPECT_NE(std::string(error.what()).find("not in the scene package"), std::string::npos);
  }
}

TEST(ScenePackage, EscapingPathsAreRefusedWithoutTouchingTheFilesystem) {
  // A package naming /etc/passwd or ../x.obj is refused by the path rules alone, even when the
  // package (built by a hostile client) carries a file under that name.
  for (const char* path : {"/etc/passwd", "../x.obj", "meshes/../../x.obj"}) {
    SCOPED_TRACE(path);
    ScenePackage package;
    package.source = "hostile.json";
    package.scene_json = std::string(R"({"format": "penumbra/scene@1",
      "camera": { "position": [0,1,3], "look_at": [0,1,0], "fov_y_deg": 40, "width": 8, "height": 8 },
      "materials": { "m": { "type": "lambert", "albedo": [0.5,0.5,0.5] } },
      "shapes": [ { "type": "obj", "file": ")") +
                         path + R"(", "material": "m" } ],
      "lights": [ { "type": "disk", "center": [0,2,0], "normal": [0,-1,0], "radius": 0.1, "radiance": [1,1,1] } ] })";
    package.files[path] = testing::tetrahedron_obj();
    try {
      parse_scene_package(package);
      FAIL() << "accepted";
    } catch (const FormatError& error) {
      EXPECT_EQ(error.json_path(), "$.shapes[0].file");
      EXPECT_NE(std::string(error.what()).find("refused OBJ path"), std::string::npos);
    }
  }
}

TEST(SceneFiles, RelativePathRules) {
  EXPECT_EQ(normalize_scene_relative_path("meshes/./a.obj"), "meshes/a.obj");
  EXPECT_EQ(normalize_scene_relative_path("meshes/sub/../a.obj"), "meshes/a.obj");
  EXPECT_EQ(normalize_scene_relative_path("a.obj"), "a.obj");
  for (const char* refused : {"", ".", "..", "../a.obj", "a/../../b.obj", "/abs/a.obj",
                              "meshes\\a.obj", "meshes/", "a/.."}) {
    EXPECT_THROW(normalize_scene_relative_path(refused), std::invalid_argument) << refused;
  }
  EXPECT_THROW(normalize_scene_relative_path(std::string("a\0b.obj", 7)), std::invalid_argument);
}

TEST(SceneFiles, SymlinkResolvingOutsideTheSceneFolderIsRefused) {
  TempDir outside;
  std::string secret = outside.write("secret.obj", testing::tetrahedron_obj());
  TempDir folder;
  std::filesystem::create_directories(folder.path() / "meshes");
  std::filesystem::create_symlink(secret, folder.path() / "meshes" / "link.obj");
  // A symlinked folder escaping the scene folder is refused the same way.
  std::filesystem::create_directory_symlink(outside.path(), folder.path() / "elsewhere");
  // A symlink that stays inside the folder is fine.
  folder.write("real/inside.obj", testing::tetrahedron_obj());
  std::filesystem::create_symlink(folder.path() / "real" / "inside.obj",
                                  folder.path() / "meshes" / "inside-link.obj");

  auto scene_naming = [&](const std::string& obj) {
    return folder.write("scene.json", std::string(R"({"format": "penumbra/scene@1",
      "camera": { "position": [0,1,3], "look_at": [0,1,0], "fov_y_deg": 40, "width": 8, "height": 8 },
      "materials": { "m": { "type": "lambert", "albedo": [0.5,0.5,0.5] } },
      "shapes": [ { "type": "obj", "file": ")") +
                                          obj + R"(", "material": "m" } ],
      "lights": [ { "type": "disk", "center": [0,2,0], "normal": [0,-1,0], "radius": 0.1, "radiance": [1,1,1] } ] })");
  };
  for (const char* escaping : {"meshes/link.obj", "elsewhere/secret.obj"}) {
    SCOPED_TRACE(escaping);
    std::string scene_path = scene_naming(escaping);
    try {
      load_scene(scene_path);
      FAIL() << "followed a symlink out of the scene folder";
    } catch (const FormatError& error) {
      EXPECT_EQ(error.json_path(), "$.shapes[0].file");
      EXPECT_NE(std::string(error.what()).find("outside the scene's folder"), std::string::npos)
          << error.what();
    }
    EXPECT_THROW(collect_scene_package(scene_path), FormatError);
  }
  EXPECT_EQ(load_scene(scene_naming("meshes/inside-link.obj")).triangle_count(), 4u);
}

TEST(SceneFiles, ObjThatFailsToLoadNamesTheFile) {
  TempDir folder;
  folder.write("empty.obj", "# nothing here\n");
  std::string scene_path = folder.write("scene.json", R"({"format": "penumbra/scene@1",
      "camera": { "position": [0,1,3], "look_at": [0,1,0], "fov_y_deg": 40, "width": 8, "height": 8 },
      "materials": { "m": { "type": "lambert", "albedo": [0.5,0.5,0.5] } },
      "shapes": [ { "type": "obj", "file": "empty.obj", "material": "m" } ],
      "lights": [ { "type": "disk", "center": [0,2,0], "normal": [0,-1,0], "radius": 0.1, "radiance": [1,1,1] } ] })");
  try {
    load_scene(scene_path);
    FAIL() << "accepted an OBJ without triangles";
  } catch (const FormatError& error) {
    EXPECT_EQ(error.json_path(), "$.shapes[0].file");
    EXPECT_NE(std::string(error.what()).find("no triangles"), std::string::npos);
    EXPECT_NE(std::string(error.what()).find("empty.obj"), std::string::npos);
  }
  // An OBJ larger than the file limit is refused before it is read.
  folder.write("empty.obj", testing::tetrahedron_obj());
  SceneLimits limits;
  limits.max_file_bytes = 2000;
  folder.write("empty.obj", std::string(4000, '#'));
  try {
    load_scene(scene_path, limits);
    FAIL() << "accepted an OBJ over the size limit";
  } catch (const FormatError& error) {
    EXPECT_NE(std::string(error.what()).find("max_file_bytes"), std::string::npos);
  }
  // A scene file over its own limit is refused before it is parsed, by either route.
  limits = SceneLimits{};
  limits.max_json_bytes = 100;
  for (auto load :
       {+[](const std::string&path, const SceneLimits&l) { load_scene(path, l); },
        +[](const std::string&path, const SceneLimits&l) { collect_scene_package(path, l); }}) {
    try {
      load(scene_path, limits);
      FAIL() << "accepted a scene over max_json_bytes";
    } catch (const FormatError& error) {
      EXPECT_NE(std::string(error.what()).find("max_json_bytes"), std::string::npos)
          << error.what();
    }
  }
}

}  // namespace
}  // namespace penumbra
