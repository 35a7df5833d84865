// The pbrt-v3 reader: every statement of the format, the shapes, lights, camera, film, sampler,
// filter and integrator mappings, and errors that name file:line:column.

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>

#include "core/math/transform.h"
#include "core/scene/pbrt_parser.h"
#include "core/scene/ply_mesh.h"
#include "core/scene/scene.h"
#include "core/scene/scene_package.h"
#include "tests/core/scene/scene_test_support.h"

namespace penumbra {
namespace {

using testing::TempDir;

// A minimal world around `body`: a camera, one quad light and WorldBegin/End.
std::string with_world(const std::string& options, const std::string& body) {
  return options + "\nWorldBegin\n" + body +
         "\nAttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [1 2 3]\n"
         "Shape \"quad\" \"point o\" [0 5 0] \"vector u\" [1 0 0] \"vector v\" [0 0 1]\n"
         "AttributeEnd\nWorldEnd\n";
}

class PbrtReader : public ::testing::Test {
 protected:
  Scene parse(const std::string& text) {
    return parse_scene(text, folder_.path().string(), "test.pbrt");
  }
  // The FormatError message of parsing `text` ("" when it parses).
  std::string error_of(const std::string& text) {
    try {
      parse(text);
    } catch (const FormatError& error) {
      return error.what();
    }
    return "";
  }
  TempDir folder_;
};

TEST(PbrtTokenizer, TokensCarryTheirLineAndColumn) {
  std::string file = "t.pbrt";
  PbrtTokenizer tokens("# comment\n  Shape \"a \\\"b\\\"\" [ -1.5e2 .5 +2 ]\n", file);
  auto word = tokens.next();
  ASSERT_TRUE(word);
  EXPECT_EQ(word->kind, PbrtTokenKind::Word);
  EXPECT_EQ(word->text, "Shape");
  EXPECT_EQ(word->location.str(), "t.pbrt:2:3");
  auto string = tokens.next();
  EXPECT_EQ(string->kind, PbrtTokenKind::String);
  EXPECT_EQ(string->text, "a \"b\"");
  EXPECT_EQ(tokens.next()->kind, PbrtTokenKind::OpenBracket);
  EXPECT_EQ(tokens.next()->number, -150);
  EXPECT_EQ(tokens.next()->number, 0.5);
  auto two = tokens.next();
  EXPECT_EQ(two->number, 2);
  EXPECT_EQ(two->location.str(), "t.pbrt:2:31");
  EXPECT_EQ(tokens.next()->kind, PbrtTokenKind::CloseBracket);
  EXPECT_FALSE(tokens.next());
}

TEST(PbrtTokenizer, MalformedTokensAreRefusedWithTheirLocation) {
  std::string file = "t.pbrt";
  auto first_error = [&](const std::string& text) {
    PbrtTokenizer tokens(text, file);
    try {
      while (tokens.next()) {
      }
    } catch (const FormatError& error) {
      return std::string(error.what());
    }
    return std::string();
  };
  EXPECT_EQ(first_error("Shape \"open"), "t.pbrt:1:7: unterminated string (no closing '\"')");
  EXPECT_EQ(first_error("\"a\nb\""),
            "t.pbrt:1:3: newline in a string (strings end on the line "
            "they start)");
  EXPECT_EQ(first_error("\"\\q\""), "t.pbrt:1:2: unknown escape \\q in a string");
  EXPECT_EQ(first_error("\n 1.2.3"), "t.pbrt:2:2: malformed number '1.2.3'");
  EXPECT_EQ(first_error("1e999"), "t.pbrt:1:1: number 1e999 is out of range");
  EXPECT_EQ(first_error("Shape @"),
            "t.pbrt:1:7: unexpected '@' (expected a statement, a quoted "
            "string, a number or a bracket)");
}

TEST_F(PbrtReader, StatementErrorsNameFileLineAndColumn) {
  EXPECT_EQ(error_of("WorldBegin\nShpe \"x\""), "test.pbrt:2:1: unknown statement 'Shpe'");
  EXPECT_EQ(error_of("worldbegin"),
            "test.pbrt:1:1: unknown statement 'worldbegin' (did you mean 'WorldBegin'?)");
  EXPECT_EQ(error_of("Translate 1 2"),
            "test.pbrt:1:14: unexpected end of file: Translate needs a number");
  EXPECT_EQ(error_of("Translate 1 \"a\" 3"),
            "test.pbrt:1:13: Translate needs a number, found the string \"a\"");
  EXPECT_EQ(error_of("Transform [1 0 0 0 1 0 0 0 1]"),
            "test.pbrt:1:29: Transform needs 16 numbers, found 9");
  EXPECT_EQ(error_of("WorldBegin\nShape \"sphere\" \"float radius\" [ 1 \"x\" ]"),
            "test.pbrt:2:35: \"float radius\" takes numbers, found the string \"x\"");
  EXPECT_EQ(error_of("WorldBegin\nShape \"sphere\" \"floaty radius\" 1"),
            "test.pbrt:2:16: unknown parameter type 'floaty' in \"floaty radius\" (expected "
            "integer, float, point2, vector2, point3, vector3, normal, rgb, xyz, blackbody, "
            "spectrum, bool, string or texture)");
  EXPECT_EQ(error_of("WorldBegin\nShape \"sphere\" \"radius\" 1"),
            "test.pbrt:2:16: parameter declaration \"radius\" of Shape is not \"type name\" "
            "(e.g. \"float fov\")");
  EXPECT_EQ(error_of("WorldBegin\nShape \"sphere\" \"float radius\" 1 \"float radius\" 2"),
            "test.pbrt:2:33: parameter 'radius' given twice to Shape (first at test.pbrt:2:16)");
  EXPECT_EQ(error_of("WorldBegin\nShape \"sphere\" \"float radius\" [ 1"),
            "test.pbrt:2:31: unterminated '[' (no closing ']') in the value of \"float radius\"");
  EXPECT_EQ(error_of("WorldBegin\nShape \"sphere\" \"bool x\" \"maybe\""),
            "test.pbrt:2:25: \"bool x\" must be \"true\" or \"false\", found \"maybe\"");
  EXPECT_EQ(error_of("WorldBegin"),
            "test.pbrt: the file ends before WorldEnd (a pbrt-v3 scene is rendered at its "
            "WorldEnd)");
  EXPECT_EQ(error_of("Shape \"sphere\""),
            "test.pbrt:1:1: Shape before WorldBegin (it belongs in the world block)");
  EXPECT_EQ(error_of("WorldBegin\nCamera \"perspective\""),
            "test.pbrt:2:1: Camera inside the world block (it belongs before WorldBegin)");
  EXPECT_EQ(error_of("WorldBegin\nAttributeEnd"),
            "test.pbrt:2:1: AttributeEnd without a matching AttributeBegin");
  EXPECT_EQ(error_of("WorldBegin\nWorldEnd"),
            "test.pbrt:2:1: the scene has no area light (Penumbra renders direct light from "
            "AreaLightSource \"diffuse\" shapes)");
}

TEST_F(PbrtReader, UnmodelledFeaturesAreRefusedWithAReason) {
  EXPECT_EQ(error_of(with_world("", "LightSource \"point\" \"rgb I\" [1 1 1]")),
            "test.pbrt:3:1: LightSource \"point\" is not modelled: Penumbra renders area lights "
            "(AreaLightSource \"diffuse\") only");
  EXPECT_EQ(error_of(with_world("Camera \"orthographic\"", "")),
            "test.pbrt:1:1: Camera \"orthographic\": camera \"orthographic\" is not modelled "
            "(Penumbra has the perspective camera)");
  EXPECT_EQ(error_of(with_world("", "Shape \"cylinder\"")),
            "test.pbrt:3:1: Shape \"cylinder\": shape \"cylinder\" is not modelled (trianglemesh, "
            "plymesh, quad, sphere and disk are)");
  EXPECT_EQ(error_of(with_world("", "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\"")),
            "test.pbrt:3:1: participating media are not modelled (Penumbra renders direct "
            "illumination between surfaces in vacuum)");
  EXPECT_EQ(error_of(with_world("PixelFilter \"mitchell\"", "")),
            "test.pbrt:1:1: PixelFilter \"mitchell\": pixel filter \"mitchell\" is not modelled "
            "(box, triangle and gaussian are; mitchell and sinc have negative lobes)");
  EXPECT_EQ(error_of(with_world("Camera \"perspective\" \"float lensradius\" 0.1", "")),
            "test.pbrt:1:22: Camera \"perspective\": \"float lensradius\": depth of field (a lens "
            "radius) is not modelled");
  EXPECT_NE(error_of(with_world("",
                                "Shape \"trianglemesh\" \"point P\" [0 0 0 1 0 0 0 1 0] "
                                "\"float alpha\" 0.5"))
                .find("alpha masks (cut-outs) are not modelled"),
            std::string::npos);
  EXPECT_NE(error_of(with_world("", "ActiveTransform StartTime"))
                .find("ActiveTransform StartTime "
                      "is not modelled"),
            std::string::npos);
}

TEST_F(PbrtReader, TransformsComposeAsInPbrt) {
  // Each mesh is one triangle at the origin, (1,0,0), (0,1,0) under a different transform.
  const std::string triangle =
      "Shape \"trianglemesh\" \"point P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2]\n";
  Scene scene = parse(with_world(
      "", "AttributeBegin Translate 1 2 3 Scale 2 2 2 " + triangle +
              "AttributeEnd\n"
              "AttributeBegin Rotate 90 0 0 1 " +
              triangle +
              "AttributeEnd\n"
              "TransformBegin Transform [1 0 0 0 0 1 0 0 0 0 1 0 5 6 7 1] " +
              triangle +
              "TransformEnd\n"
              "TransformBegin Translate 1 0 0 ConcatTransform [2 0 0 0 0 2 0 0 0 0 2 0 0 0 0 1] " +
              triangle +
              "TransformEnd\n"
              "Translate 9 9 9 CoordinateSystem \"here\" Identity " +
              triangle + "CoordSysTransform \"here\" " + triangle));
  ASSERT_EQ(scene.triangle_count(), 6u);
  auto corner = [&](size_t triangle_index, int k) {
    return scene.positions[scene.indices[3 * triangle_index + k]];
  };
  EXPECT_EQ(corner(0, 1), Vec3(3, 2, 3));  // T * S * (1,0,0)
  EXPECT_NEAR(corner(1, 1).x, 0, 1e-15);   // Rz(90) (1,0,0) = (0,1,0)
  EXPECT_NEAR(corner(1, 1).y, 1, 1e-15);
  EXPECT_EQ(corner(2, 0), Vec3(5, 6, 7));   // column-major matrix: translation in the last four
  EXPECT_EQ(corner(3, 1), Vec3(3, 0, 0));   // T(1,0,0) * S(2)
  EXPECT_EQ(corner(4, 1), Vec3(1, 0, 0));   // Identity
  EXPECT_EQ(corner(5, 1), Vec3(10, 9, 9));  // back to the named system
}

TEST_F(PbrtReader, TrianglemeshCarriesNormalsAndUvs) {
  Scene scene = parse(with_world(
      "",
      "Shape \"trianglemesh\" \"point P\" [0 0 0 1 0 0 1 1 0 0 1 0] \"integer indices\" "
      "[0 1 2 0 2 3] \"normal N\" [0 0 2 0 0 2 0 0 2 0 0 2] \"float uv\" [0 0 1 0 1 1 0 1]\n"
      "Shape \"trianglemesh\" \"point P\" [0 0 1 1 0 1 0 1 1]"));
  ASSERT_EQ(scene.triangle_count(), 3u);
  ASSERT_EQ(scene.normals.size(), scene.positions.size());
  ASSERT_EQ(scene.uvs.size(), scene.positions.size());
  EXPECT_EQ(scene.normals[0], Vec3(0, 0, 1));  // normalized
  EXPECT_EQ(scene.uvs[2].x, 1);
  EXPECT_EQ(scene.uvs[2].y, 1);
  EXPECT_EQ(scene.normals[5], Vec3(0, 0, 0));  // the second mesh has none
  EXPECT_EQ(error_of(with_world("",
                                "Shape \"trianglemesh\" \"point P\" [0 0 0 1 0 0 0 1 0] "
                                "\"integer indices\" [0 1 3]")),
            "test.pbrt:3:52: Shape \"trianglemesh\": \"integer indices\": index 3 out of range [0, "
            "3)");
}

std::string binary_ply(bool quads) {
  std::string header =
      "ply\nformat binary_little_endian 1.0\ncomment test\nelement vertex 4\n"
      "property float x\nproperty float y\nproperty float z\nproperty float nx\n"
      "property float ny\nproperty float nz\nproperty float u\nproperty float v\n"
      "element face " +
      std::string(quads ? "1" : "2") + "\nproperty list uint8 int vertex_indices\nend_header\n";
  std::string data;
  const float vertices[4][8] = {{0, 0, 0, 0, 0, 1, 0, 0},
                                {1, 0, 0, 0, 0, 1, 1, 0},
                                {1, 1, 0, 0, 0, 1, 1, 1},
                                {0, 1, 0, 0, 0, 1, 0, 1}};
  data.append(reinterpret_cast<const char*>(vertices), sizeof(vertices));
  auto face = [&](std::initializer_list<int32_t> corners) {
    data.push_back(static_cast<char>(corners.size()));
    for (int32_t c : corners) data.append(reinterpret_cast<const char*>(&c), 4);
  };
  if (quads) {
    face({0, 1, 2, 3});
  } else {
    face({0, 1, 2});
    face({0, 2, 3});
  }
  return header + data;
}

TEST(PlyMesh, BinaryAndAsciiFilesGiveTheSameMesh) {
  PlyReadResult binary = read_ply_mesh(binary_ply(true));
  std::string ascii =
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
      "property float z\nproperty float nx\nproperty float ny\nproperty float nz\n"
      "property float s\nproperty float t\nelement face 1\n"
      "property list uchar uint vertex_index\nend_header\n"
      "0 0 0 0 0 1 0 0\n1 0 0 0 0 1 1 0\n1 1 0 0 0 1 1 1\n0 1 0 0 0 1 0 1\n4 0 1 2 3\n";
  PlyReadResult text = read_ply_mesh(ascii);
  for (const PlyReadResult* r : {&binary, &text}) {
    EXPECT_EQ(r->mesh.positions.size(), 4u);
    EXPECT_EQ(r->mesh.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3}));  // quad split
    ASSERT_EQ(r->mesh.normals.size(), 4u);
    EXPECT_EQ(r->mesh.normals[3], Vec3(0, 0, 1));
    ASSERT_EQ(r->mesh.uvs.size(), 4u);
    EXPECT_EQ(r->mesh.uvs[1].x, 1);
  }
  EXPECT_EQ(read_ply_mesh(binary_ply(false)).mesh.indices, binary.mesh.indices);
}

TEST(PlyMesh, HostileFilesAreRefused) {
  auto error_of = [](const std::string& bytes) {
    try {
      read_ply_mesh(bytes);
    } catch (const std::invalid_argument& error) {
      return std::string(error.what());
    }
    return std::string();
  };
  EXPECT_EQ(error_of("obj\n"), "not a PLY file (no 'ply' line)");
  EXPECT_EQ(error_of("ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\n"),
            "PLY header line 4: the header has no end_header line");
  std::string big = binary_ply(true);
  big.replace(big.find("vertex 4"), 8, "vertex 400000000");
  EXPECT_EQ(error_of(big),
            "PLY element 'vertex' announces 400000000 records, more than the "
            "file's bytes can hold");
  std::string truncated = binary_ply(true);
  truncated.resize(truncated.size() - 3);
  EXPECT_EQ(error_of(truncated),
            "PLY data truncated (the header announces more than the file holds)");
  std::string out_of_range =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n";
  EXPECT_EQ(error_of(out_of_range), "PLY face 0 has a vertex index outside [0, 3)");
  std::string nan_vertex = out_of_range;
  nan_vertex.replace(nan_vertex.find("1 0 0\n"), 6, "nan 0 0\n");
  EXPECT_EQ(error_of(nan_vertex), "PLY vertex 1 has a non-finite value");
}

TEST_F(PbrtReader, PlymeshReadsFromTheSceneFolderAndEntersTheHash) {
  folder_.write("models/quad.ply", binary_ply(true));
  std::string text = with_world("", "Shape \"plymesh\" \"string filename\" \"models/quad.ply\"");
  std::string path = folder_.write("scene.pbrt", text);
  Scene scene = load_scene(path);
  EXPECT_EQ(scene.triangle_count(), 2u);
  EXPECT_EQ(scene.normals.size(), 4u);
  // The package route gives the same scene and hash; changing the PLY changes the hash.
  ScenePackage package = collect_scene_package(path);
  EXPECT_EQ(package.files.count("models/quad.ply"), 1u);
  Scene from_package = parse_scene_package(package);
  EXPECT_EQ(from_package.content_hash, scene.content_hash);
  EXPECT_EQ(from_package.positions, scene.positions);
  folder_.write("models/quad.ply", binary_ply(false));
  EXPECT_NE(load_scene(path).content_hash, scene.content_hash);
  // Paths may not leave the scene's folder.
  EXPECT_NE(error_of(with_world("", "Shape \"plymesh\" \"string filename\" \"../x.ply\""))
                .find("refused PLY path: path '../x.ply' leaves the scene's folder"),
            std::string::npos);
}

TEST_F(PbrtReader, IncludeFollowsFilesAndRefusesCycles) {
  folder_.write("geometry.pbrt", "Shape \"trianglemesh\" \"point P\" [0 0 0 1 0 0 0 1 0]\n");
  Scene scene = parse(with_world("", "Include \"geometry.pbrt\"\nInclude \"geometry.pbrt\""));
  EXPECT_EQ(scene.triangle_count(), 2u);
  folder_.write("loop.pbrt", "Include \"loop.pbrt\"\n");
  EXPECT_EQ(error_of(with_world("", "Include \"loop.pbrt\"")),
            "loop.pbrt:1:9: Include of 'loop.pbrt' includes itself (a cycle)");
  folder_.write("broken.pbrt", "\n  Shape 3\n");
  EXPECT_EQ(error_of(with_world("", "Include \"broken.pbrt\"")),
            "broken.pbrt:2:9: Shape needs a quoted string, found the number 3");
  EXPECT_NE(error_of(with_world("", "Include \"missing.pbrt\""))
                .find("test.pbrt:3:9: Include file cannot be read: cannot open 'missing.pbrt'"),
            std::string::npos);
}

// Every file a pbrt-v3 scene names (Include, PLY, image texture) stays inside the scene's
// folder: lexically (absolute, "..", "a/../../x") and after resolving symlinks.
TEST_F(PbrtReader, NoFilePathLeavesTheScenesFolder) {
  TempDir outside;
  outside.write("geometry.pbrt", "Shape \"trianglemesh\" \"point P\" [0 0 0 1 0 0 0 1 0]\n");
  const std::string absolute = (outside.path() / "geometry.pbrt").string();
  const std::string texture = "Texture \"t\" \"spectrum\" \"imagemap\" \"string filename\" ";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"Include \"../geometry.pbrt\"",
       "refused Include path: path '../geometry.pbrt' leaves the scene's folder"},
      {"Include \"models/../../geometry.pbrt\"",
       "refused Include path: path 'models/../../geometry.pbrt' leaves the scene's folder"},
      {"Include \"" + absolute + "\"", "refused Include path: absolute path '" + absolute + "'"},
      {"Shape \"plymesh\" \"string filename\" \"a/../../x.ply\"",
       "refused PLY path: path 'a/../../x.ply' leaves the scene's folder"},
      {texture + "\"../t.png\"", "path '../t.png' leaves the scene's folder"},
      {texture + "\"/etc/passwd\"", "absolute path '/etc/passwd'"},
  };
  for (const auto& [statement, expected] : cases)
    EXPECT_NE(error_of(with_world("", statement)).find(expected), std::string::npos)
        << statement << " -> " << error_of(with_world("", statement));
  // A symlink inside the folder to a file outside it.
  std::filesystem::create_symlink(outside.path() / "geometry.pbrt", folder_.path() / "link.pbrt");
  EXPECT_NE(error_of(with_world("", "Include \"link.pbrt\"")).find("outside the scene's folder"),
            std::string::npos)
      << error_of(with_world("", "Include \"link.pbrt\""));
}

TEST_F(PbrtReader, QuadSphereAndDiskShapes) {
  Scene scene = parse(
      with_world("",
                 "Shape \"quad\" \"point o\" [0 0 0] \"vector u\" [2 0 0] \"vector v\" [0 0 3]\n"
                 "Shape \"sphere\" \"float radius\" 0.5\nShape \"disk\" \"float radius\" 1"));
  EXPECT_EQ(scene.triangle_count(), 2u + icosphere_triangle_count(5) + 128u);
  EXPECT_EQ(scene.positions[2], Vec3(2, 0, 3));  // o + u + v
  int approximations = 0;
  for (const std::string& w : scene.warnings)
    approximations += w.find("approximated by") != std::string::npos;
  EXPECT_EQ(approximations, 2);
}

TEST_F(PbrtReader, AreaLightsBecomePenumbraLightsOnThePbrtEmittingSide) {
  // The seed's quad emits along cross(u, v): here -y.
  Scene down = parse(with_world("", ""));
  ASSERT_EQ(down.lights.size(), 1u);
  EXPECT_EQ(down.lights[0].type, LightType::Quad);
  EXPECT_EQ(down.lights[0].radiance, Rgb(1, 2, 3));
  EXPECT_EQ(down.lights[0].normal, Vec3(0, -1, 0));
  EXPECT_EQ(down.lights[0].edge1, Vec3(1, 0, 0));  // u lines stay along the file's u
  // ReverseOrientation, and a transform that swaps handedness, flip it.
  Scene reversed = parse(with_world("", "ReverseOrientation"));
  EXPECT_EQ(reversed.lights[0].normal, Vec3(0, 1, 0));
  EXPECT_EQ(reversed.lights[0].edge1, Vec3(1, 0, 0));
  // Mirrored in x, cross(u, v) turns up, and the handedness flip turns it back down.
  Scene mirrored = parse(with_world("", "Scale -1 1 1"));
  EXPECT_EQ(mirrored.lights[0].normal, Vec3(0, -1, 0));
  EXPECT_EQ(mirrored.lights[0].edge1, Vec3(-1, 0, 0));
  Scene mirrored_reversed = parse(with_world("", "Scale -1 1 1 ReverseOrientation"));
  EXPECT_EQ(mirrored_reversed.lights[0].normal, Vec3(0, 1, 0));
  // A trianglemesh parallelogram is a quad light, two-sided gives both sides, a disk a disk.
  Scene mesh = parse(
      "WorldBegin\nAreaLightSource \"diffuse\" \"rgb L\" [4 4 4] \"bool twosided\" \"true\" "
      "\"integer xsamples\" 2 \"integer ysamples\" 2\n"
      "Shape \"trianglemesh\" \"point P\" [0 0 0 1 0 0 1 1 0 0 1 0] \"integer indices\" [0 1 2 "
      "0 2 3]\nShape \"disk\" \"float height\" 2 \"float radius\" 0.5\nWorldEnd\n");
  ASSERT_EQ(mesh.lights.size(), 4u);
  EXPECT_EQ(mesh.lights[0].type, LightType::Quad);
  EXPECT_EQ(mesh.lights[0].normal, Vec3(0, 0, 1));  // counter-clockwise seen from +z
  EXPECT_EQ(mesh.lights[1].normal, Vec3(0, 0, -1));
  EXPECT_EQ(mesh.lights[2].type, LightType::Disk);
  EXPECT_EQ(mesh.lights[2].center, Vec3(0, 0, 2));
  EXPECT_EQ(mesh.lights[2].radius, 0.5);
  EXPECT_EQ(mesh.triangle_count(), 0u);  // emitters do not occlude
  // A general emissive mesh becomes one triangle light per triangle.
  Scene triangles = parse(
      "WorldBegin\nAreaLightSource \"diffuse\"\nShape \"trianglemesh\" \"point P\" "
      "[0 0 0 1 0 0 0 1 0 0 0 1] \"integer indices\" [0 1 2 0 3 1]\nWorldEnd\n");
  ASSERT_EQ(triangles.lights.size(), 2u);
  EXPECT_EQ(triangles.lights[0].type, LightType::Polygon);
  EXPECT_EQ(triangles.lights[1].vertices.size(), 3u);
}

TEST_F(PbrtReader, PerspectiveCameraAsPbrtDefinesIt) {
  // The cornell box's camera: a column-major world-to-camera matrix.
  Scene cornell =
      parse(with_world("Transform [ 1 -0 -0 -0 -0 1 -0 -0 -0 -0 -1 -0 -0 -1 6.8 1]\n"
                       "Film \"image\" \"integer xresolution\" 512 \"integer yresolution\" 512\n"
                       "Camera \"perspective\" \"float fov\" 19.5",
                       ""));
  EXPECT_EQ(cornell.camera.position, Vec3(0, 1, 6.8));
  EXPECT_EQ(normalize(cornell.camera.look_at - cornell.camera.position), Vec3(0, 0, -1));
  EXPECT_EQ(cornell.camera.up, Vec3(0, 1, 0));
  EXPECT_FALSE(cornell.camera.mirror_x);
  EXPECT_FALSE(cornell.camera.has_screen_window);
  EXPECT_EQ(cornell.camera.fov_y_deg, 19.5);
  // pbrt's LookAt builds a left-handed camera: image x is mirrored against cross(forward, up).
  Scene look = parse(with_world("LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\"", ""));
  EXPECT_EQ(look.camera.position, Vec3(0, 0, 5));
  EXPECT_TRUE(look.camera.mirror_x);
  // fov is the shorter axis's: portrait frames get an explicit screen window.
  Scene portrait =
      parse(with_world("Film \"image\" \"integer xresolution\" 100 \"integer yresolution\" 200\n"
                       "Camera \"perspective\" \"float fov\" 30",
                       ""));
  EXPECT_TRUE(portrait.camera.has_screen_window);
  EXPECT_EQ(portrait.camera.screen_x1, 1);
  EXPECT_EQ(portrait.camera.screen_y1, 2);
  // A crop window renders part of the frame.
  Scene crop = parse(with_world(
      "Film \"image\" \"integer xresolution\" 100 \"integer yresolution\" 50 \"float cropwindow\" "
      "[0.25 0.75 0 0.5]",
      ""));
  EXPECT_EQ(crop.camera.width, 50);
  EXPECT_EQ(crop.camera.height, 25);
  EXPECT_EQ(crop.camera.crop_x, 25);
  EXPECT_EQ(crop.camera.full_width, 100);
}

TEST_F(PbrtReader, SamplerFilterAndFilmSettings) {
  Scene scene = parse(with_world(
      "Sampler \"stratified\" \"integer xsamples\" 3 \"integer ysamples\" 2\n"
      "PixelFilter \"gaussian\" \"float xwidth\" 1.5 \"float ywidth\" 1 \"float alpha\" 3\n"
      "Film \"image\" \"string filename\" \"x.exr\"",
      ""));
  EXPECT_EQ(scene.render_defaults.spp, 6u);
  EXPECT_EQ(scene.render_defaults.sampler, "stratified");
  EXPECT_EQ(scene.camera.filter.type, PixelFilterType::Gaussian);
  EXPECT_EQ(scene.camera.filter.radius_x, 1.5);
  EXPECT_EQ(scene.camera.filter.alpha, 3);
  bool noted = false;
  for (const std::string& w : scene.warnings)
    noted |= w.find("Film filename ignored") != std::string::npos;
  EXPECT_TRUE(noted);
  Scene random = parse(with_world("Sampler \"random\" \"integer pixelsamples\" 16", ""));
  EXPECT_EQ(random.render_defaults.sampler, "random");
  EXPECT_EQ(random.render_defaults.spp, 16u);
  // A parameter Penumbra does not read is listed, never dropped silently.
  Scene unused = parse(with_world("Sampler \"random\" \"float dummy\" 3", ""));
  ASSERT_FALSE(unused.warnings.empty());
  EXPECT_EQ(unused.warnings[0],
            "test.pbrt:1:18: parameter \"float dummy\" of Sampler \"random\" "
            "ignored (not used by Penumbra)");
}

// The method a pbrt Integrator statement maps onto, with `samples` light samples.
class PbrtIntegrators : public PbrtReader {
 protected:
  std::string method_of(const std::string& integrator, int xsamples = 1) {
    std::string text = integrator +
                       "\nWorldBegin\nAreaLightSource \"diffuse\" \"integer xsamples\" " +
                       std::to_string(xsamples) + " \"integer ysamples\" " +
                       std::to_string(xsamples) + "\nShape \"quad\"\nWorldEnd\n";
    return parse(text).render_defaults.method;
  }
};

TEST_F(PbrtIntegrators, PointlineSettingsMapOntoTheMethodGrammar) {
  // The peer cornell box: two surface-area line directions, MIS, one sample each.
  EXPECT_EQ(method_of("Integrator \"pointline\" \"string strategy1\" \"line-surf-area\" "
                      "\"float angle1\" 0 \"string strategy2\" \"line-surf-area\" \"float angle2\" "
                      "0.5"),
            "line-area:v+line-area:u/balance");
  // The seed's surface-area angle is the lines' offset direction: angle 0 draws lines along v.
  EXPECT_EQ(method_of("Integrator \"pointline\" \"string strategy1\" \"line-surf-area\""),
            "line-area:v");
  // The kitchen: brdf + vertical solid-angle lines, 2x2 light samples split by stratification.
  EXPECT_EQ(method_of("Integrator \"pointline\" \"string strategy1\" \"brdf\" \"string strategy2\" "
                      "\"line-solid-angle\" \"float angle2\" 1 \"bool stratified\" \"true\"",
                      2),
            "2*bsdf+2*line-sa:v/balance");
  // Fig. 9's ratios: 1 point : 3 lines.
  EXPECT_EQ(method_of("Integrator \"pointline\" \"string strategy1\" \"brdf\" \"string strategy2\" "
                      "\"line-solid-angle\" \"float angle2\" 1 \"float ratio\" 0.25",
                      2),
            "bsdf+3*line-sa:v/balance");
  EXPECT_EQ(method_of("Integrator \"pointline\" \"string strategy1\" \"brdf\" \"string strategy2\" "
                      "\"line-solid-angle\" \"float angle2\" 1 \"float ratio\" 0",
                      2),
            "4*line-sa:v");
  EXPECT_EQ(method_of("Integrator \"pointline\" \"string strategy1\" \"pt-surf-area\" "
                      "\"string strategy2\" \"pt-solid-angle\" \"bool mis\" \"false\""),
            "area+sa/avg");
  EXPECT_EQ(method_of("Integrator \"pointline\" \"string strategy1\" \"brdf\" \"string strategy2\" "
                      "\"line-solid-angle\" \"string strategy3\" \"line-solid-angle\" "
                      "\"float angle3\" 1 \"float smoothstep\" 0.1"),
            "bsdf+line-sa:u+line-sa:v/smooth");
  EXPECT_EQ(method_of("Integrator \"pointline\" \"string strategy1\" \"pt-solid-angle\"", 3),
            "9*sa");
  EXPECT_EQ(method_of("Integrator \"directlighting\""), "area+bsdf/power");
  EXPECT_EQ(method_of("Integrator \"path\"", 2), "4*area+4*bsdf/power");
  EXPECT_NE(error_of("Integrator \"pointline\" \"string strategy1\" \"line-surf-area\" "
                     "\"float angle1\" 0.3\nWorldBegin\nAreaLightSource \"diffuse\"\n"
                     "Shape \"quad\"\nWorldEnd\n")
                .find("not along an edge of the light"),
            std::string::npos);
  Scene depth = parse(
      "Integrator \"pointline\" \"string strategy1\" \"brdf\" \"integer maxdepth\" "
      "3 \"float max-seconds\" 150\nWorldBegin\nAreaLightSource \"diffuse\"\n"
      "Shape \"quad\"\nWorldEnd\n");
  EXPECT_EQ(depth.max_depth, 3);
  EXPECT_EQ(depth.render_defaults.seconds, 150);
}

TEST_F(PbrtReader, MaterialsTexturesAndInstances) {
  folder_.write("textures/wood.tga", "not really an image");
  Scene scene = parse(with_world(
      "",
      "Texture \"wood\" \"spectrum\" \"imagemap\" \"string filename\" \"textures/wood.tga\"\n"
      "MakeNamedMaterial \"floor\" \"string type\" \"matte\" \"texture Kd\" \"wood\"\n"
      "MakeNamedMaterial \"white\" \"string type\" \"matte\" \"rgb Kd\" [0.8 0.7 0.6]\n"
      "ObjectBegin \"tri\"\nNamedMaterial \"white\"\n"
      "Shape \"trianglemesh\" \"point P\" [0 0 0 1 0 0 0 1 0]\nObjectEnd\n"
      "ObjectInstance \"tri\"\nTranslate 0 0 4 ObjectInstance \"tri\"\n"
      "NamedMaterial \"floor\" Shape \"quad\"\n"
      "Material \"plastic\" \"rgb Kd\" [0.1 0.2 0.3] Shape \"quad\""));
  ASSERT_EQ(scene.textures.size(), 1u);
  EXPECT_EQ(scene.textures[0].type, TextureType::ImageMap);
  EXPECT_FALSE(scene.textures[0].is_float);
  EXPECT_TRUE(scene.textures[0].gamma);  // pbrt-v3 decodes .tga files from sRGB
  ASSERT_TRUE(scene.textures[0].image);
  EXPECT_EQ(*scene.textures[0].image, "not really an image");
  ASSERT_EQ(scene.triangle_count(), 6u);
  EXPECT_EQ(scene.positions[scene.indices[3]], Vec3(0, 0, 4));  // the second instance
  // A constant matte is the exact Lambert BSDF; a textured one keeps its texture.
  const Material& white = scene.materials[scene.triangle_materials[0]];
  EXPECT_EQ(white.name, "white");
  EXPECT_EQ(white.type, MaterialType::Lambert);
  EXPECT_EQ(white.albedo, Rgb(0.8, 0.7, 0.6));
  const Material& floor = scene.materials[scene.triangle_materials[2]];
  EXPECT_EQ(floor.name, "floor");
  EXPECT_EQ(floor.type, MaterialType::Matte);
  EXPECT_EQ(floor.params.kd.texture, 0);
  const Material& plastic = scene.materials[scene.triangle_materials[4]];
  EXPECT_EQ(plastic.type, MaterialType::Plastic);
  EXPECT_EQ(plastic.params.kd.value, Rgb(0.1, 0.2, 0.3));
  EXPECT_EQ(plastic.params.ks.value, Rgb(0.25, 0.25, 0.25));  // pbrt-v3's default
  EXPECT_EQ(scene.triangle_shading.size(), scene.triangle_count());
  EXPECT_EQ(scene.triangle_shading[4], kTriangleHasUvs);  // the quad has uvs, no normals
  Scene metal = parse(with_world(
      "",
      "Material \"metal\" \"rgb eta\" [1 2 3] \"rgb k\" [4 5 6] \"float uroughness\" 0.1 "
      "\"bool remaproughness\" \"false\" Shape \"quad\""));
  const Material& m = metal.materials[metal.triangle_materials[0]];
  EXPECT_EQ(m.type, MaterialType::Metal);
  EXPECT_EQ(m.params.eta_rgb.value, Rgb(1, 2, 3));
  EXPECT_EQ(m.params.k.value, Rgb(4, 5, 6));
  EXPECT_EQ(m.params.uroughness.value, 0.1);
  EXPECT_EQ(m.params.vroughness.value, 0.01);  // metal's default roughness
  EXPECT_FALSE(m.params.remap_roughness);
  // uber's vroughness falls back to its u roughness (uroughness, else roughness), as in pbrt-v3.
  auto uber = [&](const std::string& roughness) {
    Scene s = parse(with_world("", "Material \"uber\" " + roughness + " Shape \"quad\""));
    const MaterialParams& p = s.materials[s.triangle_materials[0]].params;
    return std::make_pair(p.uroughness.value, p.vroughness.value);
  };
  EXPECT_EQ(uber("\"float uroughness\" 0.3"), std::make_pair(0.3, 0.3));
  EXPECT_EQ(uber("\"float roughness\" 0.2"), std::make_pair(0.2, 0.2));
  EXPECT_EQ(uber("\"float roughness\" 0.2 \"float uroughness\" 0.3"), std::make_pair(0.3, 0.3));
  EXPECT_EQ(uber("\"float vroughness\" 0.4"), std::make_pair(0.1, 0.4));
  // substrate reads only u and v (its default 0.1); a "roughness" is reported as unused.
  Scene substrate = parse(with_world(
      "",
      "Material \"substrate\" \"float roughness\" 0.3 \"float uroughness\" 0.2 Shape \"quad\""));
  const MaterialParams& sp = substrate.materials[substrate.triangle_materials[0]].params;
  EXPECT_EQ(sp.uroughness.value, 0.2);
  EXPECT_EQ(sp.vroughness.value, 0.1);
  bool reported = false;
  for (const std::string& w : substrate.warnings)
    reported = reported || w.find("roughness") != std::string::npos;
  EXPECT_TRUE(reported);
  Scene glass = parse(with_world("", "Material \"glass\" \"float index\" 1.33 Shape \"quad\""));
  EXPECT_EQ(glass.materials[glass.triangle_materials[0]].params.eta.value, 1.33);
  EXPECT_NE(error_of(with_world("", "Material \"hair\" Shape \"quad\""))
                .find("material type \"hair\" is not modelled"),
            std::string::npos);
  EXPECT_EQ(error_of(with_world("", "NamedMaterial \"nope\"")),
            "test.pbrt:3:15: NamedMaterial \"nope\" is not defined (no MakeNamedMaterial of that "
            "name in scope)");
  EXPECT_EQ(error_of(with_world("", "Material \"matte\" \"texture Kd\" \"nope\"")),
            "test.pbrt:3:18: Material \"matte\": \"texture Kd\": spectrum texture \"nope\" is not "
            "defined");
  EXPECT_EQ(error_of(with_world("", "ObjectInstance \"nope\"")),
            "test.pbrt:3:16: object \"nope\" is not defined (no ObjectBegin)");
}

TEST(Mat4, InverseAndRotation) {
  Mat4 t = Mat4::translate({1, 2, 3}) * Mat4::rotate(30, {1, 1, 0}) * Mat4::scale({2, 3, 4});
  std::optional<Mat4> inverse = t.inverse();
  ASSERT_TRUE(inverse);
  Mat4 product = t * *inverse;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) EXPECT_NEAR(product.m[i][j], i == j ? 1 : 0, 1e-14);
  EXPECT_FALSE(Mat4::scale({1, 0, 1}).inverse());
  EXPECT_LT(Mat4::scale({-1, 1, 1}).determinant3(), 0);
}

}  // namespace
}  // namespace penumbra
