// pbrt-v3 materials at a hit: triangle geometry, the texture graph, image maps through
// OpenImageIO (decoded as pbrt-v3 decodes them) and bump mapping.

#include "core/materials/pbrt_shading.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <memory>

namespace penumbra {
namespace {

// A unit square in z = 0 (two triangles) with uvs = (x, y).
Scene square_scene() {
  Scene s;
  s.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  s.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  s.indices = {0, 1, 2, 0, 2, 3};
  s.triangle_materials = {0, 0};
  s.triangle_shading = {kTriangleHasUvs, kTriangleHasUvs};
  return s;
}

// An uncompressed 24-bit top-left-origin TGA of w x h pixels (BGR order).
std::string tga(int w, int h, const std::vector<std::array<uint8_t, 3>>& rgb) {
  std::string out(18, '\0');
  out[2] = 2;
  out[12] = char(w & 255), out[13] = char(w >> 8);
  out[14] = char(h & 255), out[15] = char(h >> 8);
  out[16] = 24;
  out[17] = 0x20;
  for (const auto& p : rgb) {
    out.push_back(char(p[2]));
    out.push_back(char(p[1]));
    out.push_back(char(p[0]));
  }
  return out;
}

double srgb_to_linear(double v) {
  return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
}

TEST(PbrtShading, TriangleGeometryFollowsTheUvs) {
  Scene s = square_scene();
  SurfaceGeometry g = triangle_geometry(s, 0, {0.25, 0.5});  // p = 0.25 p1 + 0.5 p2
  EXPECT_NEAR(g.p.x, 0.75, 1e-15);
  EXPECT_NEAR(g.p.y, 0.5, 1e-15);
  EXPECT_NEAR(g.uv.x, 0.75, 1e-15);
  EXPECT_NEAR(g.uv.y, 0.5, 1e-15);
  EXPECT_NEAR(length(g.dpdu - Vec3{1, 0, 0}), 0, 1e-15);
  EXPECT_NEAR(length(g.dpdv - Vec3{0, 1, 0}), 0, 1e-15);
  EXPECT_NEAR(length(g.n - Vec3{0, 0, 1}), 0, 1e-15);
  // A camera ray from above with offset rays 0.01 over in x and y: du/dx = 0.01, dv/dy = 0.01.
  RayDifferential ray{{0.76, 0.5, 1}, {0, 0, -1}, {0.75, 0.51, 1}, {0, 0, -1}};
  set_footprint(g, ray);
  EXPECT_NEAR(g.dudx, 0.01, 1e-12);
  EXPECT_NEAR(g.dvdy, 0.01, 1e-12);
  EXPECT_NEAR(g.dvdx, 0, 1e-12);
  EXPECT_NEAR(g.dudy, 0, 1e-12);
}

TEST(PbrtShading, ProceduralTexturesEvaluateAsPbrt) {
  Scene s = square_scene();
  Texture c;
  c.type = TextureType::Constant;
  c.value = {0.2, 0.4, 0.6};
  Texture k;
  k.type = TextureType::Checkerboard;
  k.su = k.sv = 4;
  k.tex1 = {{1, 1, 1}, kNoTexture};
  k.tex2 = {{0, 0, 0}, 0};  // the constant texture
  Texture mix;
  mix.type = TextureType::Mix;
  mix.tex1 = {{1, 0, 0}, kNoTexture};
  mix.tex2 = {{0, 0, 1}, kNoTexture};
  mix.amount = {0.25, kNoTexture};
  Texture scale;
  scale.type = TextureType::Scale;
  scale.tex1 = {{2, 2, 2}, kNoTexture};
  scale.tex2 = {{0, 0, 0}, 0};
  s.textures = {c, k, mix, scale};
  SceneTextures tx(s);
  SurfaceGeometry g = triangle_geometry(s, 0, {0.1, 0.05});  // uv (0.15, 0.05): s, t = 0.6, 0.2
  EXPECT_EQ(tx.evaluate(1, g), (Rgb{1, 1, 1}));
  g.uv = {0.3, 0.05};  // s = 1.2: odd
  EXPECT_EQ(tx.evaluate(1, g), (Rgb{0.2, 0.4, 0.6}));
  // Box-filtered over a footprint that covers two checks half each: the mean.
  g.uv = {0.25, 0.1};  // s = 1.0 exactly at an edge, t = 0.4
  g.dudx = 0.05;       // ds = 0.2: [0.8, 1.2] in s
  g.dvdy = 0.05;  // dt = 0.2: [0.2, 0.6] in t, inside one row of checks
  g.dudy = g.dvdx = 0;
  Rgb filtered = tx.evaluate(1, g);
  for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(filtered[ch], 0.5 * (1 + c.value[ch]), 1e-12);
  EXPECT_EQ(tx.evaluate(2, g), (Rgb{0.75, 0, 0.25}));
  EXPECT_EQ(tx.evaluate(3, g), (Rgb{0.4, 0.8, 1.2}));
}

TEST(PbrtShading, ImageMapsDecodeSrgbAndFlipT) {
  Scene s = square_scene();
  Texture t;
  t.type = TextureType::ImageMap;
  t.filename = "test.tga";
  // Top row (t = 1 in pbrt's convention): red, green; bottom row (t = 0): blue, white.
  t.image = std::make_shared<std::string>(
      tga(2, 2, {{200, 0, 0}, {0, 100, 0}, {0, 0, 50}, {255, 255, 255}}));
  t.gamma = true;
  t.scale = 2;
  Texture f = t;
  f.is_float = true;
  s.textures = {t, f};
  SceneTextures tx(s);
  SurfaceGeometry g = triangle_geometry(s, 0, {0, 0});
  g.uv = {0.25, 0.75};  // the centre of the top-left texel
  Rgb red = tx.evaluate(0, g);
  EXPECT_NEAR(red.x, 2 * srgb_to_linear(200 / 255.0), 1e-5);
  EXPECT_NEAR(red.y, 0, 1e-6);
  g.uv = {0.25, 0.25};  // bottom-left: blue
  Rgb blue = tx.evaluate(0, g);
  EXPECT_NEAR(blue.z, 2 * srgb_to_linear(50 / 255.0), 1e-5);
  EXPECT_NEAR(blue.x, 0, 1e-6);
  // The float texture: the luminance before the decode, then the sRGB curve.
  g.uv = {0.75, 0.75};
  double y = 0.715160 * 100 / 255.0;
  EXPECT_NEAR(tx.evaluate(1, g).x, 2 * srgb_to_linear(y), 1e-5);
}

TEST(PbrtShading, BumpMapTiltsTheShadingNormalAgainstTheSlope) {
  Scene s = square_scene();
  // A 2x1 float image, 0 then 1 (linear, clamped): between the texel centres bilinear filtering
  // gives d(u) = 2 (u - 0.25), slope 2. pbrt-v3: dp/du' = dp/du + 2 n, so n' ~ (-2, 0, 1).
  Texture ramp;
  ramp.type = TextureType::ImageMap;
  ramp.is_float = true;
  ramp.filename = "ramp.tga";
  ramp.image = std::make_shared<std::string>(tga(2, 1, {{0, 0, 0}, {255, 255, 255}}));
  ramp.gamma = false;
  ramp.wrap = TextureWrap::Clamp;
  s.textures = {ramp};
  Material m = pbrt_material_defaults(MaterialType::Matte);
  m.params.bump = 0;
  SceneTextures tx(s);
  SurfaceGeometry g = triangle_geometry(s, 0, {0.3, 0.2});  // uv (0.5, 0.2)
  apply_bump(m, g, tx);
  Vec3 expected = normalize(Vec3{-2, 0, 1});
  EXPECT_NEAR(length(g.ns - expected), 0, 1e-4);
  // The BSDF's frame follows the bumped normal; the geometric normal stays.
  SurfaceBsdf bsdf = pbrt_surface_bsdf(m, triangle_geometry(s, 0, {0.3, 0.2}), tx);
  EXPECT_NEAR(length(bsdf.shading_frame().n - expected), 0, 1e-4);
  EXPECT_NEAR(length(bsdf.geometric_normal() - Vec3{0, 0, 1}), 0, 1e-15);
}

}  // namespace
}  // namespace penumbra
