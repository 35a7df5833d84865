#pragma once
// The material data model beyond the three JSON materials of SCENE_FORMAT.md: pbrt-v3's
// materials (Pharr, Jakob, Humphreys, "Physically Based Rendering", 3rd ed., ch. 9) with
// parameters that are constants or textures, and the texture graph of its ch. 10 (imagemap,
// constant, scale, mix, checkerboard). Plain data: scene readers fill it, core/materials
// evaluates it (textures once per shading point, with the camera ray's footprint, into a
// per-hit BSDF).
//
// Names and meanings follow pbrt-v3's parameter lists; pbrt_material_defaults() gives a
// material of each type with pbrt-v3's defaults, so a reader sets only what a file gives.
//
//   type       lobes (pbrt-v3)                                    parameters used
//   matte      Lambert (sigma = 0) or Oren-Nayar (sigma > 0, deg)  kd, sigma
//   plastic    Lambert + Trowbridge-Reitz, dielectric Fresnel      kd, ks, roughness (u = v)
//              with pbrt-v3's eta pair (1.5, 1)
//   substrate  FresnelBlend (Ashikhmin-Shirley, Trowbridge-Reitz)  kd, ks, uroughness, vroughness
//   metal      Trowbridge-Reitz, conductor Fresnel                 eta_rgb, k, u/vroughness
//   mirror     specular reflection (no Fresnel)                    kr
//   glass      specular reflection + transmission, dielectric      kr, kt, eta
//   uber       opacity < 1: a pass-through specular transmission   kd, ks, kr, kt, opacity,
//              of 1 - opacity; Lambert, Trowbridge-Reitz, specular  u/vroughness, eta
//              reflection and transmission scaled by opacity
//
// Every material may have a bump map (a float texture: pbrt-v3's displacement, Sec. 9.3) and
// `remap_roughness` (pbrt-v3's TrowbridgeReitzDistribution::RoughnessToAlpha) for its
// microfacet roughnesses. Reflectances are clamped to >= 0 when evaluated, as pbrt-v3 does.

#include <cstdint>
#include <memory>
#include <string>

#include "core/math/vec.h"

namespace penumbra {

inline constexpr int32_t kNoTexture = -1;

// A spectrum (RGB) parameter: `value`, unless `texture` is the index of a spectrum texture of
// Scene::textures.
struct SpectrumParam {
  Rgb value{0, 0, 0};
  int32_t texture = kNoTexture;
};

// A float parameter: `value`, unless `texture` is the index of a float texture.
struct FloatParam {
  double value = 0;
  int32_t texture = kNoTexture;
};

enum class TextureType { Constant, Scale, Mix, Checkerboard, ImageMap };
enum class TextureWrap { Repeat, Black, Clamp };

// One node of the texture graph. A float texture's value is its x component (constants and
// operands of float textures hold theirs in value.x); its operands are float textures, a
// spectrum texture's are spectrum textures. A texture refers only to textures before it in
// Scene::textures (pbrt-v3 defines a texture before its use), so the graph has no cycle.
struct Texture {
  std::string name;
  TextureType type = TextureType::Constant;
  bool is_float = false;
  // pbrt-v3's "uv" mapping (the only one modelled): (s, t) = (su u + du, sv v + dv).
  double su = 1, sv = 1, du = 0, dv = 0;

  // constant: value.
  Rgb value{1, 1, 1};
  // scale: tex1 * tex2. mix: (1 - amount) tex1 + amount tex2. checkerboard (2D): tex1 where
  // floor(s) + floor(t) is even, tex2 where it is odd.
  SpectrumParam tex1, tex2;
  FloatParam amount{0.5};
  // checkerboard "aamode": "closedform" (true, pbrt-v3's default: the checks box-filtered over
  // the footprint) or "none" (false: point sampled).
  bool checker_filtered = true;

  // imagemap: the image file's bytes (read by the scene reader, or from a scene package) and its
  // name (for messages; its extension names the format). 8-bit images are decoded from sRGB
  // when `gamma` (pbrt-v3's default: true for .tga and .png files), then multiplied by `scale`;
  // a float texture takes the luminance of the RGB texels before that decode, as pbrt-v3 does.
  // Filtered by trilinear MIP-mapping (`trilinear`, as the scenes ask) or anisotropic filtering
  // of at most `max_anisotropy` (where pbrt-v3 uses EWA), over the camera ray's footprint.
  std::string filename;
  std::shared_ptr<const std::string> image;
  bool gamma = true;
  double scale = 1;
  TextureWrap wrap = TextureWrap::Repeat;
  bool trilinear = false;
  double max_anisotropy = 8;
};

// The parameters of the pbrt-v3 materials (see the table above for which each type uses).
struct MaterialParams {
  SpectrumParam kd, ks, kr, kt;
  SpectrumParam opacity;     // uber
  SpectrumParam eta_rgb, k;  // metal: the conductor's index of refraction and absorption
  FloatParam eta;            // glass, uber: the dielectric's index of refraction ("index")
  FloatParam sigma;          // matte: Oren-Nayar's sigma in degrees (clamped to [0, 90])
  // Microfacet roughness along the shading frame's s (dp/du) and t axes; alpha itself unless
  // remap_roughness (then RoughnessToAlpha(roughness)). plastic: u and v are its "roughness".
  FloatParam uroughness, vroughness;
  bool remap_roughness = true;
  int32_t bump = kNoTexture;  // "bumpmap": a float texture, or none
};

}  // namespace penumbra
