#pragma once
// A pbrt-v3 material at a ray's hit on a scene triangle: the hit's differential geometry as
// pbrt-v3's Triangle::Intersect computes it, its texture footprint from the ray's differentials
// (SurfaceInteraction::ComputeDifferentials), the textures of the material's parameters
// (core/scene/material_model.h; image maps filtered by OpenImageIO's TextureSystem), bump mapping
// (Material::Bump) and the resulting SurfaceBsdf.
//
// Geometry (pbrt-v3 conventions):
//   - uv: the triangle's per-vertex uvs, or (0,0), (1,0), (1,1) without them; dp/du, dp/dv
//     solved from the uv differences (a coordinate system around the normal when degenerate).
//   - geometric normal n = normalize(cross(p1 - p0, p2 - p0)) (the reader baked pbrt-v3's
//     orientation into the winding); with vertex normals the shading normal is their
//     interpolation and n is flipped to its side (orientation is the shading normal's), shading
//     dp/du = s = normalize(dp/du) made perpendicular to it, dp/dv = t = cross(ns, s), and
//     dn/du, dn/dv solved from the vertex normals; without them the shading frame is the
//     geometric one (dp/du, dp/dv as solved, dn = 0).
//   - footprint: the offset rays' hits on the tangent plane give dp/dx, dp/dy, and du/dx ..
//     dv/dy by least squares in the two coordinates where n is smallest (pbrt-v3's choice).
//
// Textures (pbrt-v3 ch. 10): (s, t) = (su u + du, sv v + dv); constant, scale (tex1 tex2), mix
// ((1 - amount) tex1 + amount tex2), checkerboard (2D: tex1 where floor(s) + floor(t) is even;
// "closedform": pbrt-v3's box-filtered checks over the footprint), imagemap: texels decoded once
// at load (8-bit sRGB to linear when `gamma`, pbrt-v3's InverseGammaCorrect, then times `scale`;
// a float texture takes the luminance first), MIP-mapped by OpenImageIO (box-filtered levels),
// looked up with t flipped (pbrt-v3 puts t = 0 at the image's bottom row), trilinear when the
// file asks, else anisotropic (OpenImageIO's, where pbrt-v3 uses EWA) with its max anisotropy.
//
// Bump mapping: d displaced along the shading normal, as pbrt-v3's Material::Bump: the texture is
// evaluated at (u + du, v) and (u, v + dv) with du = (|du/dx| + |du/dy|) / 2 (0.0005 when 0),
// dp/du' = dp/du + (d(u + du) - d(u)) / du ns + d dn/du (and v alike), ns' = normalize(cross(
// dp/du', dp/dv')) faced to the geometric normal.

#include <memory>
#include <string>

#include "core/materials/pbrt_material.h"
#include "core/materials/surface_bsdf.h"
#include "core/scene/scene.h"

namespace penumbra {

// A ray with its two offset rays (one pixel apart in x and in y, already scaled by the scene's
// texture footprint factor). Without differentials textures are point-sampled at the finest
// level.
struct RayDifferential {
  Vec3 dx_origin, dx_direction;
  Vec3 dy_origin, dy_direction;
};

struct SurfaceGeometry {
  Vec3 p;
  Vec3 n;   // geometric normal on the outside (unit)
  Vec3 ns;  // shading normal on the outside (unit)
  Vec2 uv;
  Vec3 dpdu, dpdv;                  // geometric
  Vec3 shading_dpdu, shading_dpdv;  // shading
  Vec3 dndu, dndv;                  // shading normal's derivatives
  double dudx = 0, dvdx = 0, dudy = 0, dvdy = 0;
};

// The geometry of `triangle` at barycentric (b1, b2) (weights of vertices 1 and 2).
SurfaceGeometry triangle_geometry(const Scene& scene, uint32_t triangle, const Vec2& barycentric);
// Sets the footprint from the ray's differentials (pbrt-v3's ComputeDifferentials).
void set_footprint(SurfaceGeometry& g, const RayDifferential& ray);

// The scene's textures, ready to evaluate (image maps decoded and MIP-mapped once). Thread-safe.
class SceneTextures {
 public:
  // Throws FormatError naming the texture when an image cannot be decoded.
  explicit SceneTextures(const Scene& scene);
  ~SceneTextures();
  SceneTextures(const SceneTextures&) = delete;
  SceneTextures& operator=(const SceneTextures&) = delete;

  Rgb spectrum(const SpectrumParam& p, const SurfaceGeometry& g) const;
  double number(const FloatParam& p, const SurfaceGeometry& g) const;
  Rgb evaluate(int32_t texture, const SurfaceGeometry& g) const;

 private:
  struct Impl;
  const Scene* scene_;
  std::unique_ptr<Impl> impl_;
};

// The material's parameters at the hit (textures evaluated).
PbrtMaterialValues material_values(const Material& material, const SurfaceGeometry& g,
                                   const SceneTextures& textures);
// Applies the material's bump map to g's shading frame (no-op without one).
void apply_bump(const Material& material, SurfaceGeometry& g, const SceneTextures& textures);
// The material's BSDF at the hit (bump map applied).
SurfaceBsdf pbrt_surface_bsdf(const Material& material, SurfaceGeometry g,
                              const SceneTextures& textures);

}  // namespace penumbra
