// The `penumbra/scene@1` reader: the SCENE_FORMAT.md example parses with every field as written,
// and each kind of bad input is refused with a FormatError naming the JSON path and the problem.

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <nlohmann/json.hpp>
#include <random>
#include <string>

#include "core/scene/scene.h"
#include "scene_test_support.h"

namespace penumbra {
namespace {

using nlohmann::json;
using testing::kFormatExample;
using testing::TempDir;

// The format example with its OBJ file in a fresh folder.
class FormatExample : public ::testing::Test {
 protected:
  void SetUp() override { folder_.write("meshes/bunny.obj", testing::tetrahedron_obj()); }
  Scene parse(const std::string& text) const {
    return parse_scene(text, folder_.path().string(), "example.json");
  }
  // Parses the example after `edit` changed it; the error it must raise is checked by callers.
  Scene parse_edited(const std::function<void(json&)>& edit) const {
    json document = json::parse(kFormatExample);
    edit(document);
    return parse(document.dump());
  }
  TempDir folder_;
};

TEST_F(FormatExample, ParsesEveryFieldAsWritten) {
  Scene scene = parse(kFormatExample);
  EXPECT_EQ(scene.name, "cornell-occluders");
  EXPECT_EQ(scene.camera.position, Vec3(0, 1, 3.5));
  EXPECT_EQ(scene.camera.look_at, Vec3(0, 1, 0));
  EXPECT_EQ(scene.camera.up, Vec3(0, 1, 0));
  EXPECT_EQ(scene.camera.fov_y_deg, 40);
  EXPECT_EQ(scene.camera.width, 512);
  EXPECT_EQ(scene.camera.height, 512);

  ASSERT_EQ(scene.materials.size(), 3u);
  auto material = [&](const std::string& name) -> const Material& {
    for (const Material& m : scene.materials)
      if (m.name == name) return m;
    ADD_FAILURE() << "no material " << name;
    return scene.materials.front();
  };
  EXPECT_EQ(material("white").type, MaterialType::Lambert);
  EXPECT_EQ(material("white").albedo, Rgb(0.8, 0.8, 0.8));
  EXPECT_EQ(material("shiny").type, MaterialType::Phong);
  EXPECT_EQ(material("shiny").kd, Rgb(0.1, 0.1, 0.1));
  EXPECT_EQ(material("shiny").ks, Rgb(0.6, 0.6, 0.6));
  EXPECT_EQ(material("shiny").exponent, 200);
  EXPECT_EQ(material("metal").type, MaterialType::Ggx);
  EXPECT_EQ(material("metal").diffuse, Rgb(0.05, 0.05, 0.05));
  EXPECT_EQ(material("metal").specular, Rgb(0.9, 0.9, 0.9));
  EXPECT_EQ(material("metal").roughness, 0.1);

  // quad 2 + box 12 + icosphere(4) 5120 + triangles 1 + tetrahedron 4.
  EXPECT_EQ(scene.triangle_count(), 2u + 12u + 5120u + 1u + 4u);
  EXPECT_EQ(scene.triangle_materials.size(), scene.triangle_count());
  for (uint32_t index : scene.indices) EXPECT_LT(index, scene.positions.size());
  for (uint32_t m : scene.triangle_materials) EXPECT_LT(m, scene.materials.size());
  // The sphere's triangles carry the metal material, the others white.
  size_t metal_triangles = 0;
  for (uint32_t m : scene.triangle_materials) metal_triangles += scene.materials[m].name == "metal";
  EXPECT_EQ(metal_triangles, 5120u);

  ASSERT_EQ(scene.lights.size(), 4u);
  EXPECT_EQ(scene.lights[0].type, LightType::Quad);
  EXPECT_EQ(scene.lights[0].radiance, Rgb(10, 10, 10));
  EXPECT_EQ(scene.lights[0].profile, ProfileType::Constant);
  EXPECT_EQ(scene.lights[1].type, LightType::Polygon);
  EXPECT_EQ(scene.lights[1].vertices.size(), 4u);
  EXPECT_EQ(scene.lights[2].type, LightType::Disk);
  EXPECT_DOUBLE_EQ(scene.lights[2].radius, 0.2);
  EXPECT_EQ(scene.lights[2].normal, Vec3(0, -1, 0));
  EXPECT_EQ(scene.lights[3].profile, ProfileType::Gaussian);
  EXPECT_DOUBLE_EQ(scene.lights[3].sigma, 0.25);
  for (const Light& light : scene.lights) {
    EXPECT_NEAR(light.normal.y, -1.0, 1e-12);  // every example light faces down
    EXPECT_GT(light.area, 0);
  }

  ASSERT_EQ(scene.regions.size(), 2u);
  const Region& penumbra = scene.regions.at("penumbra");
  EXPECT_EQ(penumbra.x0, 120);
  EXPECT_EQ(penumbra.y0, 300);
  EXPECT_EQ(penumbra.x1, 220);
  EXPECT_EQ(penumbra.y1, 400);
  EXPECT_TRUE(scene.warnings.empty());
  EXPECT_EQ(scene.content_hash.size(), 64u);
}

TEST_F(FormatExample, OptionalKeysTakeTheirDefaults) {
  Scene scene = parse_edited([](json& s) {
    s["shapes"][2].erase("subdivisions");
    s["shapes"][4].erase("scale");
    s["shapes"][4].erase("translate");
    s["camera"].erase("up");
    s["materials"]["shiny"].erase("kd");
    s["materials"]["metal"].erase("diffuse");
    s.erase("regions");
    s.erase("name");
  });
  EXPECT_EQ(scene.triangle_count(), 2u + 12u + 1280u + 1u + 4u);  // subdivisions 3
  EXPECT_EQ(scene.camera.up, Vec3(0, 1, 0));
  EXPECT_TRUE(scene.regions.empty());
  EXPECT_EQ(scene.name, "example");  // from the source name "example.json"
  for (const Material& m : scene.materials) {
    if (m.name == "shiny") {
      EXPECT_EQ(m.kd, Rgb(0, 0, 0));
    }
    if (m.name == "metal") {
      EXPECT_EQ(m.diffuse, Rgb(0, 0, 0));
    }
  }
}

TEST_F(FormatExample, ObjScaleAndTranslateApply) {
  Scene scene = parse_edited([](json& s) {
    s["shapes"] = json::array({s["shapes"][4]});
    s["shapes"][0]["scale"] = 2;
    s["shapes"][0]["translate"] = {10, 20, 30};
  });
  ASSERT_EQ(scene.triangle_count(), 4u);
  // Tetrahedron corners (0,0,0), (1,0,0), (0,1,0), (0,0,1) become 2p + (10,20,30).
  std::vector<Vec3> expected = {{10, 20, 30}, {12, 20, 30}, {10, 22, 30}, {10, 20, 32}};
  EXPECT_EQ(scene.positions, expected);
}

TEST_F(FormatExample, DescriptionAndUnknownOptionalKeysAreAccepted) {
  Scene scene = parse_edited([](json& s) {
    s["description"] = "mirrors a figure";
    s["future_key"] = 1;
    s["shapes"][0]["future_shape_key"] = true;
  });
  EXPECT_EQ(scene.description, "mirrors a figure");
  ASSERT_EQ(scene.warnings.size(), 2u);
  EXPECT_NE(scene.warnings[0].find("$.future_key"), std::string::npos);
  EXPECT_NE(scene.warnings[1].find("$.shapes[0].future_shape_key"), std::string::npos);
}

// One bad input: how to break the example, the JSON path the error must name, and a word of the
// message saying what is wrong.
struct BadInput {
  const char* label;
  std::function<void(json&)> edit;
  std::string path;
  std::string word;
};

TEST_F(FormatExample, RefusesEachBadInputWithPathAndReason) {
  const double nan = std::nan("");
  const std::vector<BadInput> cases = {
      {"unknown format version", [](json& s) { s["format"] = "penumbra/scene@2"; }, "$.format",
       "unsupported"},
      {"not a scene", [](json& s) { s["format"] = "penumbra/probe@1"; }, "$.format", "not a scene"},
      {"missing camera", [](json& s) { s.erase("camera"); }, "$.camera", "missing required key"},
      {"misspelled required key",
       [](json& s) {
         s["lights"][2]["raduis"] = s["lights"][2]["radius"];
         s["lights"][2].erase("radius");
       },
       "$.lights[2].radius", "missing required key"},
      {"wrong type", [](json& s) { s["camera"]["width"] = "512"; }, "$.camera.width", "expected"},
      {"wrong vector size",
       [](json& s) {
         s["camera"]["position"] = {0, 1};
       },
       "$.camera.position", "3 numbers"},
      {"non-integral size", [](json& s) { s["camera"]["width"] = 511.5; }, "$.camera.width",
       "integer"},
      {"zero width", [](json& s) { s["camera"]["width"] = 0; }, "$.camera.width", "at least 1"},
      {"absurd resolution", [](json& s) { s["camera"]["height"] = 100000; }, "$.camera.height",
       "max_resolution"},
      {"fov out of range", [](json& s) { s["camera"]["fov_y_deg"] = 180; }, "$.camera.fov_y_deg",
       "fov"},
      {"camera without direction",
       [](json& s) { s["camera"]["look_at"] = s["camera"]["position"]; }, "$.camera.look_at",
       "coincides"},
      {"up parallel to view",
       [](json& s) {
         s["camera"]["up"] = {0, 0, 1};
       },
       "$.camera", "parallel"},
      {"NaN coordinate", [nan](json& s) { s["shapes"][0]["origin"][1] = nan; },
       "$.shapes[0].origin[1]", "expected a number"},
      {"absurd coordinate", [](json& s) { s["lights"][0]["origin"][0] = 1e9; },
       "$.lights[0].origin", "max_coordinate"},
      {"albedo above 1", [](json& s) { s["materials"]["white"]["albedo"][1] = 1.5; },
       "$.materials.white.albedo", "[0, 1]"},
      {"negative ks", [](json& s) { s["materials"]["shiny"]["ks"][0] = -0.1; },
       "$.materials.shiny.ks", "[0, 1]"},
      {"zero exponent", [](json& s) { s["materials"]["shiny"]["exponent"] = 0; },
       "$.materials.shiny.exponent", "positive"},
      {"zero roughness", [](json& s) { s["materials"]["metal"]["roughness"] = 0; },
       "$.materials.metal.roughness", "(0, 1]"},
      {"roughness above 1", [](json& s) { s["materials"]["metal"]["roughness"] = 1.5; },
       "$.materials.metal.roughness", "(0, 1]"},
      {"unknown material type", [](json& s) { s["materials"]["white"]["type"] = "velvet"; },
       "$.materials.white.type", "unknown material type"},
      {"unknown material reference", [](json& s) { s["shapes"][1]["material"] = "gold"; },
       "$.shapes[1].material", "unknown material"},
      {"unknown shape type", [](json& s) { s["shapes"][0]["type"] = "cone"; }, "$.shapes[0].type",
       "unknown shape type"},
      {"degenerate shape quad",
       [](json& s) {
         s["shapes"][0]["edge2"] = {4, 0, 0};
       },
       "$.shapes[0]", "degenerate"},
      {"inverted box", [](json& s) { s["shapes"][1]["max"][1] = 0.4; }, "$.shapes[1].max",
       "empty box"},
      {"zero sphere radius", [](json& s) { s["shapes"][2]["radius"] = 0; }, "$.shapes[2].radius",
       "positive"},
      {"absurd subdivisions", [](json& s) { s["shapes"][2]["subdivisions"] = 30; },
       "$.shapes[2].subdivisions", "max_sphere_subdivisions"},
      {"negative subdivisions", [](json& s) { s["shapes"][2]["subdivisions"] = -1; },
       "$.shapes[2].subdivisions", ">= 0"},
      {"triangle index out of range", [](json& s) { s["shapes"][3]["indices"][2] = 3; },
       "$.shapes[3].indices[2]", "out of range"},
      {"ragged triangle indices", [](json& s) { s["shapes"][3]["indices"].push_back(0); },
       "$.shapes[3].indices", "3 per triangle"},
      {"OBJ file missing", [](json& s) { s["shapes"][4]["file"] = "meshes/dragon.obj"; },
       "$.shapes[4].file", "cannot"},
      {"OBJ path leaves the folder", [](json& s) { s["shapes"][4]["file"] = "../bunny.obj"; },
       "$.shapes[4].file", "leaves"},
      {"OBJ path escapes after a detour",
       [](json& s) { s["shapes"][4]["file"] = "meshes/../../etc/passwd"; }, "$.shapes[4].file",
       "leaves"},
      {"absolute OBJ path", [](json& s) { s["shapes"][4]["file"] = "/etc/passwd"; },
       "$.shapes[4].file", "absolute"},
      {"zero OBJ scale", [](json& s) { s["shapes"][4]["scale"] = 0; }, "$.shapes[4].scale",
       "positive"},
      {"no lights", [](json& s) { s["lights"] = json::array(); }, "$.lights", "at least one"},
      {"unknown light type", [](json& s) { s["lights"][0]["type"] = "spot"; }, "$.lights[0].type",
       "unknown light type"},
      {"negative radiance", [](json& s) { s["lights"][1]["radiance"][2] = -1; },
       "$.lights[1].radiance", "negative"},
      {"zero-area quad light",
       [](json& s) {
         s["lights"][0]["edge2"] = {0, 0, 0};
       },
       "$.lights[0]", "zero"},
      {"parallel quad light edges",
       [](json& s) {
         s["lights"][0]["edge2"] = {1, 0, 0};
       },
       "$.lights[0]", "parallel"},
      {"polygon with 2 vertices",
       [](json& s) {
         s["lights"][1]["vertices"] = {{0, 2, 0}, {1, 2, 0}};
       },
       "$.lights[1].vertices", "at least 3"},
      {"collinear polygon",
       [](json& s) {
         s["lights"][1]["vertices"] = {{0, 2, 0}, {1, 2, 0}, {2, 2, 0}};
       },
       "$.lights[1]", "collinear"},
      {"non-planar polygon", [](json& s) { s["lights"][1]["vertices"][3][1] = 2.1; }, "$.lights[1]",
       "non-planar"},
      {"non-convex polygon",
       [](json& s) {
         s["lights"][1]["vertices"] = {{0, 2, 0}, {0, 2, 1}, {1, 2, 1}, {0.2, 2, 0.8}, {1, 2, 0}};
       },
       "$.lights[1]", "non-convex"},
      {"self-intersecting polygon (pentagram)",
       [](json& s) {
         json star = json::array();
         for (int k = 0; k < 5; ++k) {
           double angle = -4 * M_PI * k / 5;  // every second corner of a pentagon
           star.push_back({std::cos(angle), 2, std::sin(angle)});
         }
         s["lights"][1]["vertices"] = star;
       },
       "$.lights[1]", "non-convex"},
      {"gaussian profile on a polygon",
       [](json& s) {
         s["lights"][1]["profile"] = {{"type", "gaussian"}, {"sigma", 0.3}};
       },
       "$.lights[1].profile.type", "quad and disk"},
      {"zero disk radius", [](json& s) { s["lights"][2]["radius"] = 0; }, "$.lights[2].radius",
       "positive"},
      {"zero disk normal",
       [](json& s) {
         s["lights"][2]["normal"] = {0, 0, 0};
       },
       "$.lights[2].normal", "zero"},
      {"zero gaussian sigma", [](json& s) { s["lights"][3]["profile"]["sigma"] = 0; },
       "$.lights[3].profile.sigma", "positive"},
      {"unknown profile", [](json& s) { s["lights"][3]["profile"]["type"] = "cosine"; },
       "$.lights[3].profile.type", "unknown profile"},
      {"region outside the image",
       [](json& s) {
         s["regions"]["glossy"] = {300, 100, 600, 200};
       },
       "$.regions.glossy", "outside"},
      {"negative region corner",
       [](json& s) {
         s["regions"]["glossy"] = {-1, 100, 60, 200};
       },
       "$.regions.glossy", "outside"},
      {"empty region",
       [](json& s) {
         s["regions"]["glossy"] = {300, 100, 300, 200};
       },
       "$.regions.glossy", "empty"},
      {"region of 3 numbers",
       [](json& s) {
         s["regions"]["glossy"] = {300, 100, 400};
       },
       "$.regions.glossy", "[x0, y0, x1, y1]"},
      {"region name with spaces",
       [](json& s) {
         s["regions"]["my crop"] = {0, 0, 0, 10};
       },
       "$.regions[\"my crop\"]", "empty"},
  };
  for (const BadInput& bad : cases) {
    SCOPED_TRACE(bad.label);
    try {
      parse_edited(bad.edit);
      ADD_FAILURE() << "accepted: " << bad.label;
    } catch (const FormatError& error) {
      EXPECT_EQ(error.json_path(), bad.path) << error.what();
      EXPECT_NE(std::string(error.what()).find(bad.word), std::string::npos) << error.what();
      EXPECT_NE(std::string(error.what()).find("example.json"), std::string::npos)
          << "the message names the source file: " << error.what();
    }
  }
}

TEST_F(FormatExample, MisspelledRequiredKeyIsNamedInTheError) {
  try {
    parse_edited([](json& s) {
      s["lights"][2]["raduis"] = 0.2;
      s["lights"][2].erase("radius");
    });
    FAIL() << "accepted a misspelled required key";
  } catch (const FormatError& error) {
    EXPECT_NE(std::string(error.what()).find("'raduis'"), std::string::npos) << error.what();
  }
}

TEST_F(FormatExample, TooManyTrianglesNamesTheLimit) {
  SceneLimits limits;
  limits.max_triangles = 1000;  // the example's icosphere alone has 5120
  try {
    parse_scene(kFormatExample, folder_.path().string(), "example.json", limits);
    FAIL() << "accepted too many triangles";
  } catch (const FormatError& error) {
    EXPECT_EQ(error.json_path(), "$.shapes[2]");
    EXPECT_NE(std::string(error.what()).find("max_triangles"), std::string::npos);
  }
  limits = SceneLimits{};
  limits.max_lights = 3;
  EXPECT_THROW(parse_scene(kFormatExample, folder_.path().string(), "example.json", limits),
               FormatError);
}

// Every JSON pointer to a leaf or member of `value`, for random edits.
void collect_pointers(const json& value, const json::json_pointer& at,
                      std::vector<json::json_pointer>& out) {
  out.push_back(at);
  if (value.is_object())
    for (const auto& [key, member] : value.items()) collect_pointers(member, at / key, out);
  if (value.is_array())
    for (size_t i = 0; i < value.size(); ++i) collect_pointers(value[i], at / i, out);
}

TEST_F(FormatExample, RandomEditsEitherParseOrRaiseFormatError) {
  // Robustness: thousands of random edits (bad values, wrong types, deleted keys) never crash
  // the reader or escape as another exception, and whatever parses keeps the Scene invariants.
  json base = json::parse(kFormatExample);
  base["shapes"][2]["subdivisions"] = 1;  // keep each parse cheap
  std::vector<json::json_pointer> pointers;
  collect_pointers(base, json::json_pointer(), pointers);
  const std::vector<json> replacements = {0,
                                          -1,
                                          1e-300,
                                          1e300,
                                          0.5,
                                          3,
                                          "x",
                                          nullptr,
                                          true,
                                          json::array(),
                                          json::object(),
                                          json::array({1, 2, 3})};
  std::mt19937 random(20261123);
  int parsed = 0, refused = 0;
  for (int trial = 0; trial < 600; ++trial) {
    json edited = base;
    for (int edit = 0; edit < 1 + trial % 3; ++edit) {
      const json::json_pointer& target = pointers[random() % pointers.size()];
      if (!edited.contains(target) || target.empty()) continue;
      json& parent = edited[target.parent_pointer()];
      if (random() % 4 == 0 && parent.is_object())
        parent.erase(target.back());
      else
        edited[target] = replacements[random() % replacements.size()];
    }
    try {
      Scene scene = parse_scene(edited.dump(), folder_.path().string(), "example.json");
      ++parsed;
      for (uint32_t index : scene.indices) ASSERT_LT(index, scene.positions.size());
      for (const Vec3& p : scene.positions) ASSERT_TRUE(is_finite(p));
      ASSERT_EQ(scene.triangle_materials.size(), scene.triangle_count());
      for (const Light& light : scene.lights) {
        ASSERT_TRUE(std::isfinite(light.area) && light.area > 0);
        ASSERT_NEAR(length(light.normal), 1.0, 1e-12);
        ASSERT_TRUE(is_finite(light.radiance));
      }
    } catch (const FormatError&) {
      ++refused;
    } catch (const std::exception& other) {
      FAIL() << "trial " << trial << " escaped as " << other.what() << "\n" << edited.dump();
    }
  }
  EXPECT_GT(parsed, 20);
  EXPECT_GT(refused, 300);
}

TEST(SceneReader, RefusesBrokenJsonWithItsPosition) {
  try {
    parse_scene("{\"format\": \"penumbra/scene@1\", ", ".", "broken.json");
    FAIL() << "accepted broken JSON";
  } catch (const FormatError& error) {
    EXPECT_EQ(error.json_path(), "$");
    EXPECT_NE(std::string(error.what()).find("invalid JSON"), std::string::npos);
    EXPECT_NE(std::string(error.what()).find("broken.json"), std::string::npos);
  }
  // A number that overflows a double is refused as a whole document, naming the number.
  try {
    parse_scene(R"({"format": "penumbra/scene@1", "camera": {"fov_y_deg": 1e999}})", ".",
                "overflow.json");
    FAIL() << "accepted an overflowing number";
  } catch (const FormatError& error) {
    EXPECT_EQ(error.json_path(), "$");
    EXPECT_NE(std::string(error.what()).find("1e999"), std::string::npos) << error.what();
  }
  EXPECT_THROW(parse_scene("[1, 2, 3]", ".", "array.json"), FormatError);
  EXPECT_THROW(parse_scene("", ".", "empty.json"), FormatError);
}

TEST(SceneReader, RefusesDeepNestingWithoutOverflowingTheStack) {
  // A million nested arrays would overflow a recursive parser; the reader refuses before parsing.
  std::string deep(1'000'000, '[');
  deep += std::string(1'000'000, ']');
  try {
    parse_scene(deep, ".", "deep.json");
    FAIL() << "accepted deep nesting";
  } catch (const FormatError& error) {
    EXPECT_EQ(error.json_path(), "$");
    EXPECT_NE(std::string(error.what()).find("nesting"), std::string::npos);
  }
  // Brackets inside strings do not count as nesting.
  std::string in_string =
      R"({"format": "penumbra/scene@1", "name": ")" + std::string(100, '[') + R"("})";
  try {
    parse_scene(in_string, ".", "strings.json");
    FAIL() << "accepted a scene without camera";
  } catch (const FormatError& error) {
    EXPECT_EQ(error.json_path(), "$.camera");  // got past the nesting check and the name
  }
}

TEST(SceneReader, LoadSceneReportsUnreadableFile) {
  try {
    load_scene("/nonexistent/penumbra/scene.json");
    FAIL() << "loaded a missing file";
  } catch (const FormatError& error) {
    EXPECT_NE(std::string(error.what()).find("/nonexistent/penumbra/scene.json"),
              std::string::npos);
  }
}

TEST(SceneReader, ZeroAreaTrianglesAreDroppedWithAWarning) {
  TempDir folder;
  std::string text = R"({
    "format": "penumbra/scene@1",
    "camera": { "position": [0,1,3], "look_at": [0,1,0], "fov_y_deg": 40, "width": 8, "height": 8 },
    "materials": { "m": { "type": "lambert", "albedo": [0.5,0.5,0.5] } },
    "shapes": [ { "type": "triangles", "positions": [[0,0,0],[1,0,0],[0,1,0],[2,0,0]],
                  "indices": [0,1,2, 0,1,3, 2,2,1], "material": "m" } ],
    "lights": [ { "type": "disk", "center": [0,5,0], "normal": [0,-1,0], "radius": 1, "radiance": [1,1,1] } ]
  })";
  Scene scene = parse_scene(text, folder.path().string(), "degenerate.json");
  EXPECT_EQ(scene.triangle_count(), 1u);  // (0,1,3) is collinear, (2,2,1) repeats a vertex
  ASSERT_EQ(scene.warnings.size(), 1u);
  EXPECT_NE(scene.warnings[0].find("$.shapes[0]: dropped 2"), std::string::npos);
}

TEST(SceneReader, CameraFieldsAndNonSquareImage) {
  TempDir folder;
  std::string text = R"({
    "format": "penumbra/scene@1",
    "camera": { "position": [1,2,3], "look_at": [1,2,0], "fov_y_deg": 19.5, "width": 320, "height": 1 },
    "materials": {}, "shapes": [],
    "lights": [ { "type": "disk", "center": [0,5,0], "normal": [0,-3,0], "radius": 1, "radiance": [1,1,1] } ],
    "regions": { "row": [0, 0, 320, 1] }
  })";
  Scene scene = parse_scene(text, folder.path().string(), "camera.json");
  EXPECT_EQ(scene.camera.position, Vec3(1, 2, 3));
  EXPECT_EQ(scene.camera.fov_y_deg, 19.5);
  EXPECT_EQ(scene.camera.width, 320);
  EXPECT_EQ(scene.camera.height, 1);
  EXPECT_EQ(scene.triangle_count(), 0u);
  EXPECT_EQ(scene.lights[0].normal, Vec3(0, -1, 0));  // normalized
  EXPECT_NEAR(scene.lights[0].area, M_PI, 1e-15);
}

}  // namespace
}  // namespace penumbra
