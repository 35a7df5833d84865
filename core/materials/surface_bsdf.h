#pragma once
// The BSDF of a pbrt-v3 material at one shading point: its lobes (pbrt-v3's BxDFs, PBR 3rd ed.
// ch. 8) with every texture already evaluated, in the hit's shading frame. Built by
// core/materials/pbrt_material.h; used through the shading point (core/lights/shading_point.h)
// by every strategy and, for its delta lobes, by the specular chains of the renderer.
//
// Lobes (local frame: z = shading normal on the surface's outside, x = shading tangent s):
//   lambert            R / pi
//   oren-nayar         R / pi (A + B max(0, cos(phi_i - phi_o)) sin(alpha) tan(beta)),
//                      A = 1 - s^2 / (2 (s^2 + 0.33)), B = 0.45 s^2 / (s^2 + 0.09), s = sigma (rad)
//   microfacet         R D(h) G(wo, wi) F(wi . h) / (4 |cos_o| |cos_i|), h = normalize(wo + wi)
//                      faced to +z for F; F dielectric (pbrt's FrDielectric with eta_i, eta_t) or
//                      conductor (FrConductor with eta, k)
//   fresnel-blend      28 / (23 pi) Rd (1 - Rs) (1 - (1 - |cos_i|/2)^5) (1 - (1 - |cos_o|/2)^5)
//                      + D(h) / (4 |wi.h| max(|cos_i|, |cos_o|)) Schlick(wi.h; Rs)
//   specular-reflection   delta: wi = (-wo.x, -wo.y, wo.z), f |cos_i| = F(cos_i) R (F = 1 without
//                         a Fresnel term: pbrt's FresnelNoOp)
//   specular-transmission delta: refraction by eta_a (outside) / eta_b (inside), f |cos_i| =
//                         T (1 - F) (eta_incident / eta_transmitted)^2 (radiance transport)
// D and G are the anisotropic Trowbridge-Reitz distribution of core/materials/microfacet.h.
//
// As in pbrt-v3's BSDF::f, the lobes are evaluated with |cos| in the shading frame, and whether
// wi is reflected or transmitted is decided by the geometric normal: every non-delta lobe here
// reflects, so f is 0 unless wo and wi lie on the same side of the geometric normal (pbrt-v3's
// rough glass transmission is not modelled: pbrt_material.h refuses it).
//
// Sampling (non-delta lobes only): a lobe is chosen in proportion to its weight (the luminance
// of its reflectance), then lambert and oren-nayar draw a cosine-weighted direction on wo's side
// of the shading normal, microfacet draws a visible normal (Heitz 2018) and reflects wo about it,
// fresnel-blend does either with probability 1/2 (as pbrt-v3). When the shading normal differs
// from the geometric normal a defensive cosine lobe about the geometric normal takes
// kDefensiveFraction of the samples, so the density is positive wherever f is (directions above
// the geometric surface but below the shading horizon included) and f |cos_s| / pdf stays an
// unbiased estimator for the BSDF strategy alone. pdf() is the whole mixture; a draw that lands
// where f is 0 is a failed sample (empty).

#include <cstdint>
#include <optional>

#include "core/materials/microfacet.h"
#include "core/math/vec.h"

namespace penumbra {

enum class LobeType : uint8_t {
  Lambert,
  OrenNayar,
  Microfacet,
  FresnelBlend,
  SpecularReflection,
  SpecularTransmission
};
enum class FresnelType : uint8_t { None, Dielectric, Conductor };

struct BsdfLobe {
  LobeType type = LobeType::Lambert;
  FresnelType fresnel = FresnelType::None;
  Rgb r{0, 0, 0};                // R; T (transmission); Rd (fresnel-blend)
  Rgb rs{0, 0, 0};               // fresnel-blend: Rs
  Rgb eta{1, 1, 1}, k{0, 0, 0};  // conductor Fresnel
  double eta_i = 1, eta_t = 1;   // dielectric Fresnel; transmission: eta_a (outside), eta_b
  double on_a = 1, on_b = 0;     // oren-nayar A, B
  TrowbridgeReitz distribution;  // microfacet, fresnel-blend

  static BsdfLobe lambert(const Rgb& r);
  static BsdfLobe oren_nayar(const Rgb& r, double sigma_degrees);
  static BsdfLobe microfacet_dielectric(const Rgb& r, const TrowbridgeReitz& d, double eta_i,
                                        double eta_t);
  static BsdfLobe microfacet_conductor(const Rgb& r, const TrowbridgeReitz& d, const Rgb& eta,
                                       const Rgb& k);
  static BsdfLobe fresnel_blend(const Rgb& rd, const Rgb& rs, const TrowbridgeReitz& d);
  // Mirror reflection without a Fresnel term (pbrt's FresnelNoOp).
  static BsdfLobe specular_reflection(const Rgb& r);
  static BsdfLobe specular_reflection_dielectric(const Rgb& r, double eta_i, double eta_t);
  static BsdfLobe specular_transmission(const Rgb& t, double eta_a, double eta_b);

  bool is_delta() const {
    return type == LobeType::SpecularReflection || type == LobeType::SpecularTransmission;
  }

  // The lobe in the local frame (pbrt-v3's BxDF::f, Pdf, Sample_f); non-delta lobes only.
  Rgb f(const Vec3& wo, const Vec3& wi) const;
  double pdf(const Vec3& wo, const Vec3& wi) const;
  std::optional<Vec3> sample(const Vec3& wo, const Vec2& u) const;
};

// One delta lobe's direction at a shading point: radiance arriving along wi contributes
// weight * L (the lobe's f |cos_s| / pdf).
struct SpecularBranch {
  Vec3 wi;
  Rgb weight;
};

class SurfaceBsdf {
 public:
  static constexpr int kMaxLobes = 6;
  static constexpr double kDefensiveFraction = 0.1;

  SurfaceBsdf() = default;
  // `shading`: orthonormal, shading.n the shading normal on the surface's outside;
  // `geometric_normal`: unit, on the same side as shading.n.
  SurfaceBsdf(const Frame& shading, const Vec3& geometric_normal);

  // Adds a lobe (at most kMaxLobes; more is a programming error and is ignored).
  void add(const BsdfLobe& lobe);

  int lobe_count() const { return count_; }
  const BsdfLobe& lobe(int i) const { return lobes_[i]; }
  bool has_non_delta() const { return non_delta_count_ > 0; }
  bool has_delta() const { return count_ > non_delta_count_; }
  const Frame& shading_frame() const { return shading_; }
  const Vec3& geometric_normal() const { return ng_; }

  // The non-delta lobes' f(wo, wi) (world directions, unit, away from the surface).
  Rgb f(const Vec3& wo, const Vec3& wi) const;
  // f(wo, wi) |cos(shading normal, wi)| / |cos(geometric normal, wi)|: what an estimator that
  // multiplies by the geometric cosine needs to obtain pbrt-v3's f |cos_s| (0 where that cosine
  // is 0).
  Rgb f_for_geometric_cosine(const Vec3& wo, const Vec3& wi) const;
  // Density of sample() in solid angle.
  double pdf(const Vec3& wo, const Vec3& wi) const;
  // A direction drawn from the non-delta lobes with its density (empty: a failed draw).
  struct Sample {
    Vec3 wi;
    double pdf = 0;
  };
  std::optional<Sample> sample(const Vec3& wo, const Vec2& u) const;

  // The delta lobes' directions for wo (a refraction that is totally internally reflected gives
  // none). Returns how many were written to `out`.
  int specular_branches(const Vec3& wo, SpecularBranch out[kMaxLobes]) const;

 private:
  bool reflects(const Vec3& wo, const Vec3& wi) const;

  Frame shading_{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  Vec3 ng_{0, 0, 1};
  bool defensive_ = false;
  BsdfLobe lobes_[kMaxLobes];
  double weights_[kMaxLobes] = {};  // sampling weights of the non-delta lobes (0 for delta)
  double non_delta_weight_ = 0;
  int count_ = 0;
  int non_delta_count_ = 0;
};

}  // namespace penumbra
