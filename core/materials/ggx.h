#pragma once
// The GGX (Trowbridge-Reitz) microfacet lobe of the `ggx` material, as free functions in the
// local shading frame (z = normal), so that other parts (e.g. an LTC fitter) use the very same
// lobe. Isotropic; `alpha` is the GGX roughness, clamped to [kGgxMinAlpha, inf) by callers.
//
// Forms used (Heitz 2014, "Understanding the masking-shadowing function"):
//   D(h)   = alpha^2 / (pi (h.x^2 + h.y^2 + alpha^2 h.z^2)^2)
//   Lambda = (sqrt(1 + alpha^2 tan^2 theta) - 1) / 2
//   G1(w)  = 1 / (1 + Lambda(w)),  G2(wo, wi) = 1 / (1 + Lambda(wo) + Lambda(wi)) (height-corr.)
// Every product with 1/cos theta is written as a whole (cos * Lambda = alpha^2 sin^2 /
// (2 (cos + sqrt(cos^2 + alpha^2 sin^2)))) so grazing directions give finite values.

#include "core/math/vec.h"

namespace penumbra {

inline constexpr double kGgxMinAlpha = 1e-4;

// D(h) for a unit half vector h in the local frame.
double ggx_distribution(const Vec3& h_local, double alpha);
// cos(theta) * Lambda(w) for cos(theta) = c in (0, 1].
double ggx_cos_times_lambda(double c, double alpha);
// G1(w) / cos(theta_w) for cos(theta_w) = c in (0, 1].
double ggx_g1_over_cos(double c, double alpha);
// The microfacet term D F G2 / (4 cos_o cos_i) without F: D G2 / (4 cos_o cos_i).
double ggx_specular_without_fresnel(const Vec3& wo_local, const Vec3& wi_local, double alpha);
// Schlick's Fresnel with F0 per channel, for cos = dot(wi, h).
Rgb schlick_fresnel(const Rgb& f0, double cos_theta);
// Heitz 2018, "Sampling the GGX distribution of visible normals": a half vector drawn with
// density D_wo(h) = G1(wo) max(0, wo.h) D(h) / cos_o, for wo_local.z > 0.
Vec3 sample_ggx_visible_normal(const Vec3& wo_local, double alpha, const Vec2& u);
// The same with anisotropic roughness (alpha_x along the local x axis, alpha_y along y).
Vec3 sample_ggx_visible_normal(const Vec3& wo_local, double alpha_x, double alpha_y, const Vec2& u);
// Density of wi = reflect(wo, h) with h from sample_ggx_visible_normal, in solid angle:
// D_wo(h) / (4 |wo.h|) = G1(wo) D(h) / (4 cos_o). Zero below the horizon.
double ggx_reflection_pdf(const Vec3& wo_local, const Vec3& wi_local, double alpha);

}  // namespace penumbra
