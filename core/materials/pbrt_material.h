#pragma once
// pbrt-v3's materials (core/scene/material_model.h) as lobes of a SurfaceBsdf, following
// pbrt-v3's Material::ComputeScatteringFunctions (PBR 3rd ed. ch. 9) as its direct-lighting
// integrator calls them (one lobe per BxDF, glass as separate specular reflection and
// transmission):
//
//   matte      Kd > 0: lambert (sigma = 0) or oren-nayar(sigma clamped to [0, 90] degrees)
//   plastic    lambert(Kd) + microfacet(Ks, TR(r, r), dielectric Fresnel eta_i 1.5, eta_t 1 --
//              pbrt-v3's own pair)
//   substrate  fresnel-blend(Kd, Ks, TR(u, v)) when Kd or Ks is not black
//   metal      microfacet(1, TR(u, v), conductor Fresnel eta, k)
//   mirror     specular-reflection(Kr) without Fresnel
//   glass      specular-reflection(Kr, dielectric 1 | index) + specular-transmission(Kt, 1 | index)
//              (rough glass is refused by pbrt_material_unsupported)
//   uber       opacity o < 1: specular-transmission(1 - o, 1 | 1) (the pass-through); then
//              lambert(o Kd), microfacet(o Ks, TR(u, v), dielectric 1 | eta),
//              specular-reflection(o Kr, dielectric 1 | eta), specular-transmission(o Kt, 1 | eta)
//
// Reflectances are clamped to >= 0 (pbrt-v3's Spectrum::Clamp); black lobes are not added.
// Roughnesses pass through pbrt_roughness_to_alpha when `remap_roughness`. The JSON materials
// (lambert, phong, ggx) are not handled here (core/materials/bsdf.h).

#include <optional>
#include <string>

#include "core/materials/surface_bsdf.h"
#include "core/scene/scene.h"

namespace penumbra {

// A material's parameters at one shading point (textures evaluated).
struct PbrtMaterialValues {
  Rgb kd, ks, kr, kt, opacity, eta_rgb, k;
  double eta = 1.5, sigma = 0, uroughness = 0, vroughness = 0;
};

// The parameters of a material whose parameters are all constants (textures ignored: their
// parameter's constant `value` is taken).
PbrtMaterialValues constant_material_values(const MaterialParams& params);

// Is `type` one of pbrt-v3's materials (matte .. uber)?
bool is_pbrt_material(MaterialType type);

// Why a pbrt-v3 material cannot be rendered exactly (empty when it can): rough glass with a
// transmission (pbrt-v3's MicrofacetTransmission lights the surface from behind, which the
// direct-lighting estimator does not model).
std::optional<std::string> pbrt_material_unsupported(const Material& material);

// The lobes of `material` (a pbrt-v3 type) with `values`, in the frame given.
SurfaceBsdf make_pbrt_bsdf(const Material& material, const PbrtMaterialValues& values,
                           const Frame& shading, const Vec3& geometric_normal);

}  // namespace penumbra
