#pragma once
// The microfacet and Fresnel pieces of pbrt-v3's materials (Pharr, Jakob, Humphreys, "Physically
// Based Rendering", 3rd ed., Sec. 8.2 and 8.4), in the local shading frame (z = shading normal,
// x along the surface's u direction). Double precision.
//
// Anisotropic Trowbridge-Reitz (GGX) with alpha_x along x and alpha_y along y:
//   D(h)     = 1 / (pi ax ay (h.x^2 / ax^2 + h.y^2 / ay^2 + h.z^2)^2)
//   Lambda   = (sqrt(1 + alpha(phi)^2 tan^2 theta) - 1) / 2,  alpha(phi)^2 tan^2 theta =
//              (ax^2 w.x^2 + ay^2 w.y^2) / w.z^2
//   G(wo,wi) = 1 / (1 + Lambda(wo) + Lambda(wi))    (pbrt-v3's height-correlated form)
// Each product with 1 / |cos theta| is written as a whole (|cos| Lambda = a / (2 (|cos| +
// sqrt(cos^2 + a))), a = ax^2 w.x^2 + ay^2 w.y^2), so grazing directions stay finite. pbrt-v3
// clamps both alphas to at least 1e-3 (kTrowbridgeReitzMinAlpha) when it builds the distribution.
//
// Sampling draws visible normals exactly (Heitz 2018, "Sampling the GGX distribution of visible
// normals", stretched by ax, ay), with density D_wo(h) = G1(wo) max(0, wo.h) D(h) / |wo.z|.
// (pbrt-v3 samples the same density through a fitted inversion; the density is what matters.)

#include "core/math/vec.h"

namespace penumbra {

inline constexpr double kTrowbridgeReitzMinAlpha = 1e-3;

// pbrt-v3's TrowbridgeReitzDistribution::RoughnessToAlpha: roughness clamped to >= 1e-3, then a
// quartic polynomial in x = ln(roughness).
double pbrt_roughness_to_alpha(double roughness);

struct TrowbridgeReitz {
  double alpha_x = 0.1, alpha_y = 0.1;

  // Both alphas clamped to at least kTrowbridgeReitzMinAlpha (NaN becomes the minimum).
  static TrowbridgeReitz make(double alpha_x, double alpha_y);

  // D(h) for a unit h (either hemisphere: D(-h) = D(h), as pbrt-v3's cos^2 form).
  double d(const Vec3& h) const;
  // |w.z| Lambda(w) for a unit w.
  double cos_times_lambda(const Vec3& w) const;
  // G1(w) / |w.z|; finite for w.z -> 0 (0 when w.z == 0 exactly and w is tangent).
  double g1_over_cos(const Vec3& w) const;
  // G(wo, wi) / (|wo.z| |wi.z|): 0 when either is tangent.
  double g_over_cos_cos(const Vec3& wo, const Vec3& wi) const;
  // A visible normal for wo (any hemisphere: for wo.z < 0 the normal is drawn for -wo and
  // negated, as pbrt-v3 does), u in [0, 1)^2.
  Vec3 sample_visible_normal(const Vec3& wo, const Vec2& u) const;
  // Density of h drawn by sample_visible_normal, per solid angle of h: G1(wo) |wo.h| D(h) / |wo.z|.
  double visible_normal_pdf(const Vec3& wo, const Vec3& h) const;
};

// pbrt-v3's FrDielectric: unpolarized Fresnel reflectance for cos_i in [-1, 1] measured on the
// side of eta_i; a negative cosine means the light arrives from the eta_t side (indices swapped).
// Total internal reflection gives 1.
double fresnel_dielectric(double cos_i, double eta_i, double eta_t);

// pbrt-v3's FrConductor with eta_i = 1: reflectance of a conductor of index eta and absorption
// k (per channel) at |cos_i|.
Rgb fresnel_conductor(double cos_i, const Rgb& eta, const Rgb& k);

}  // namespace penumbra
