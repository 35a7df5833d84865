#include "core/materials/pbrt_material.h"

#include <algorithm>
#include <cmath>

namespace penumbra {
namespace {

Rgb clamp_low(const Rgb& c) {
  Rgb out;
  for (int i = 0; i < 3; ++i) out[i] = c[i] > 0 ? c[i] : 0.0;  // NaN becomes 0
  return out;
}

TrowbridgeReitz distribution(double u, double v, bool remap) {
  if (remap) {
    u = pbrt_roughness_to_alpha(u);
    v = pbrt_roughness_to_alpha(v);
  }
  return TrowbridgeReitz::make(u, v);
}

}  // namespace

PbrtMaterialValues constant_material_values(const MaterialParams& p) {
  PbrtMaterialValues v;
  v.kd = p.kd.value;
  v.ks = p.ks.value;
  v.kr = p.kr.value;
  v.kt = p.kt.value;
  v.opacity = p.opacity.value;
  v.eta_rgb = p.eta_rgb.value;
  v.k = p.k.value;
  v.eta = p.eta.value;
  v.sigma = p.sigma.value;
  v.uroughness = p.uroughness.value;
  v.vroughness = p.vroughness.value;
  return v;
}

bool is_pbrt_material(MaterialType type) {
  switch (type) {
    case MaterialType::Matte:
    case MaterialType::Plastic:
    case MaterialType::Substrate:
    case MaterialType::Metal:
    case MaterialType::Mirror:
    case MaterialType::Glass:
    case MaterialType::Uber:
      return true;
    default:
      return false;
  }
}

std::optional<std::string> pbrt_material_unsupported(const Material& m) {
  if (m.type != MaterialType::Glass) return std::nullopt;
  const MaterialParams& p = m.params;
  bool rough = p.uroughness.texture != kNoTexture || p.vroughness.texture != kNoTexture ||
               p.uroughness.value != 0 || p.vroughness.value != 0;
  bool transmits = p.kt.texture != kNoTexture || !is_black(clamp_low(p.kt.value));
  if (rough && transmits)
    return "glass '" + m.name +
           "': rough transmission (uroughness or vroughness > 0 with Kt not black) lights the "
           "surface from behind, which direct lighting here does not model; use roughness 0 or "
           "Kt 0";
  return std::nullopt;
}

SurfaceBsdf make_pbrt_bsdf(const Material& m, const PbrtMaterialValues& v, const Frame& shading,
                           const Vec3& geometric_normal) {
  SurfaceBsdf bsdf(shading, geometric_normal);
  const bool remap = m.params.remap_roughness;
  switch (m.type) {
    case MaterialType::Matte: {
      Rgb r = clamp_low(v.kd);
      double sigma = std::clamp(std::isfinite(v.sigma) ? v.sigma : 0.0, 0.0, 90.0);
      if (!is_black(r))
        bsdf.add(sigma == 0 ? BsdfLobe::lambert(r) : BsdfLobe::oren_nayar(r, sigma));
      break;
    }
    case MaterialType::Plastic: {
      Rgb kd = clamp_low(v.kd), ks = clamp_low(v.ks);
      if (!is_black(kd)) bsdf.add(BsdfLobe::lambert(kd));
      if (!is_black(ks))
        bsdf.add(BsdfLobe::microfacet_dielectric(
            ks, distribution(v.uroughness, v.uroughness, remap), 1.5, 1.0));
      break;
    }
    case MaterialType::Substrate: {
      Rgb kd = clamp_low(v.kd), ks = clamp_low(v.ks);
      if (!is_black(kd) || !is_black(ks))
        bsdf.add(BsdfLobe::fresnel_blend(kd, ks, distribution(v.uroughness, v.vroughness, remap)));
      break;
    }
    case MaterialType::Metal:
      bsdf.add(BsdfLobe::microfacet_conductor(
          {1, 1, 1}, distribution(v.uroughness, v.vroughness, remap), v.eta_rgb, v.k));
      break;
    case MaterialType::Mirror: {
      Rgb kr = clamp_low(v.kr);
      if (!is_black(kr)) bsdf.add(BsdfLobe::specular_reflection(kr));
      break;
    }
    case MaterialType::Glass: {
      Rgb kr = clamp_low(v.kr), kt = clamp_low(v.kt);
      bool specular = v.uroughness == 0 && v.vroughness == 0;
      if (!is_black(kr)) {
        if (specular)
          bsdf.add(BsdfLobe::specular_reflection_dielectric(kr, 1.0, v.eta));
        else
          bsdf.add(BsdfLobe::microfacet_dielectric(
              kr, distribution(v.uroughness, v.vroughness, remap), 1.0, v.eta));
      }
      // Rough transmission is refused up front (pbrt_material_unsupported).
      if (!is_black(kt) && specular) bsdf.add(BsdfLobe::specular_transmission(kt, 1.0, v.eta));
      break;
    }
    case MaterialType::Uber: {
      Rgb op = clamp_low(v.opacity);
      Rgb pass = clamp_low(Rgb(1, 1, 1) - op);
      if (!is_black(pass)) bsdf.add(BsdfLobe::specular_transmission(pass, 1.0, 1.0));
      Rgb kd = op * clamp_low(v.kd);
      if (!is_black(kd)) bsdf.add(BsdfLobe::lambert(kd));
      Rgb ks = op * clamp_low(v.ks);
      if (!is_black(ks))
        bsdf.add(BsdfLobe::microfacet_dielectric(
            ks, distribution(v.uroughness, v.vroughness, remap), 1.0, v.eta));
      Rgb kr = op * clamp_low(v.kr);
      if (!is_black(kr)) bsdf.add(BsdfLobe::specular_reflection_dielectric(kr, 1.0, v.eta));
      Rgb kt = op * clamp_low(v.kt);
      if (!is_black(kt)) bsdf.add(BsdfLobe::specular_transmission(kt, 1.0, v.eta));
      break;
    }
    default:
      break;
  }
  return bsdf;
}

}  // namespace penumbra
