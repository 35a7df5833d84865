#include "core/materials/surface_bsdf.h"

#include <algorithm>
#include <cmath>

namespace penumbra {
namespace {

constexpr double kOneMinusEpsilon = 0x1.fffffffffffffp-1;

Vec3 sample_cosine_hemisphere(const Vec2& u) {
  double r = std::sqrt(u.x);
  double phi = 2.0 * kPi * u.y;
  return {r * std::cos(phi), r * std::sin(phi), safe_sqrt(1.0 - u.x)};
}

bool same_hemisphere(const Vec3& a, const Vec3& b) {
  return a.z * b.z > 0;
}

double sin_theta(const Vec3& w) {
  return safe_sqrt(1.0 - w.z * w.z);
}
double cos_phi(const Vec3& w, double sin_t) {
  return sin_t == 0 ? 1.0 : std::clamp(w.x / sin_t, -1.0, 1.0);
}
double sin_phi(const Vec3& w, double sin_t) {
  return sin_t == 0 ? 0.0 : std::clamp(w.y / sin_t, -1.0, 1.0);
}

double pow5(double v) {
  return (v * v) * (v * v) * v;
}

Rgb clamp_finite(const Rgb& c) {
  Rgb out;
  for (int i = 0; i < 3; ++i) out[i] = std::isfinite(c[i]) ? std::max(0.0, c[i]) : 0.0;
  return out;
}

// Weight of a non-delta lobe when choosing which one samples: the luminance of its reflectance,
// never 0 (every lobe keeps a positive share, so the density is positive wherever f is).
double sampling_weight(const BsdfLobe& lobe);
double reflectance_luminance(const BsdfLobe& lobe) {
  switch (lobe.type) {
    case LobeType::Lambert:
    case LobeType::OrenNayar:
      return std::max(0.0, luminance(lobe.r));
    case LobeType::Microfacet:
      if (lobe.fresnel == FresnelType::Conductor)
        return std::max(0.0, luminance(lobe.r * fresnel_conductor(1.0, lobe.eta, lobe.k)));
      return std::max(0.0, luminance(lobe.r));
    case LobeType::FresnelBlend:
      return std::max(0.0, luminance(lobe.r)) + std::max(0.0, luminance(lobe.rs));
    default:
      return 0;
  }
}
double sampling_weight(const BsdfLobe& lobe) {
  double w = reflectance_luminance(lobe);
  return std::isfinite(w) ? std::max(w, 1e-6) : 1e-6;
}

// Refraction of wo (local) through the plane z = 0 with relative index eta = eta_i / eta_t,
// about the normal n on wo's side. Empty under total internal reflection.
std::optional<Vec3> refract(const Vec3& wo, const Vec3& n, double eta) {
  double cos_i = dot(n, wo);
  double sin2_i = std::max(0.0, 1.0 - cos_i * cos_i);
  double sin2_t = eta * eta * sin2_i;
  if (!(sin2_t < 1)) return std::nullopt;
  double cos_t = std::sqrt(1.0 - sin2_t);
  return eta * -wo + (eta * cos_i - cos_t) * n;
}

}  // namespace

BsdfLobe BsdfLobe::lambert(const Rgb& r) {
  BsdfLobe lobe;
  lobe.type = LobeType::Lambert;
  lobe.r = r;
  return lobe;
}

BsdfLobe BsdfLobe::oren_nayar(const Rgb& r, double sigma_degrees) {
  BsdfLobe lobe;
  lobe.type = LobeType::OrenNayar;
  lobe.r = r;
  double sigma = sigma_degrees * kPi / 180.0;
  double sigma2 = sigma * sigma;
  lobe.on_a = 1.0 - sigma2 / (2.0 * (sigma2 + 0.33));
  lobe.on_b = 0.45 * sigma2 / (sigma2 + 0.09);
  return lobe;
}

BsdfLobe BsdfLobe::microfacet_dielectric(const Rgb& r, const TrowbridgeReitz& d, double eta_i,
                                         double eta_t) {
  BsdfLobe lobe;
  lobe.type = LobeType::Microfacet;
  lobe.fresnel = FresnelType::Dielectric;
  lobe.r = r;
  lobe.distribution = d;
  lobe.eta_i = eta_i;
  lobe.eta_t = eta_t;
  return lobe;
}

BsdfLobe BsdfLobe::microfacet_conductor(const Rgb& r, const TrowbridgeReitz& d, const Rgb& eta,
                                        const Rgb& k) {
  BsdfLobe lobe;
  lobe.type = LobeType::Microfacet;
  lobe.fresnel = FresnelType::Conductor;
  lobe.r = r;
  lobe.distribution = d;
  lobe.eta = eta;
  lobe.k = k;
  return lobe;
}

BsdfLobe BsdfLobe::fresnel_blend(const Rgb& rd, const Rgb& rs, const TrowbridgeReitz& d) {
  BsdfLobe lobe;
  lobe.type = LobeType::FresnelBlend;
  lobe.r = rd;
  lobe.rs = rs;
  lobe.distribution = d;
  return lobe;
}

BsdfLobe BsdfLobe::specular_reflection(const Rgb& r) {
  BsdfLobe lobe;
  lobe.type = LobeType::SpecularReflection;
  lobe.r = r;
  return lobe;
}

BsdfLobe BsdfLobe::specular_reflection_dielectric(const Rgb& r, double eta_i, double eta_t) {
  BsdfLobe lobe = specular_reflection(r);
  lobe.fresnel = FresnelType::Dielectric;
  lobe.eta_i = eta_i;
  lobe.eta_t = eta_t;
  return lobe;
}

BsdfLobe BsdfLobe::specular_transmission(const Rgb& t, double eta_a, double eta_b) {
  BsdfLobe lobe;
  lobe.type = LobeType::SpecularTransmission;
  lobe.fresnel = FresnelType::Dielectric;
  lobe.r = t;
  lobe.eta_i = eta_a;
  lobe.eta_t = eta_b;
  return lobe;
}

Rgb BsdfLobe::f(const Vec3& wo, const Vec3& wi) const {
  switch (type) {
    case LobeType::Lambert:
      return r * kInvPi;
    case LobeType::OrenNayar: {
      double sin_i = sin_theta(wi), sin_o = sin_theta(wo);
      double max_cos = 0;
      if (sin_i > 1e-4 && sin_o > 1e-4) {
        double d_cos =
            cos_phi(wi, sin_i) * cos_phi(wo, sin_o) + sin_phi(wi, sin_i) * sin_phi(wo, sin_o);
        max_cos = std::max(0.0, d_cos);
      }
      double sin_alpha, tan_beta;
      double abs_ci = std::abs(wi.z), abs_co = std::abs(wo.z);
      if (abs_ci > abs_co) {
        sin_alpha = sin_o;
        tan_beta = sin_i / abs_ci;
      } else {
        sin_alpha = sin_i;
        // |cos_o| == 0 only with |cos_i| == 0 too: then sin_alpha = 1 and max_cos may be > 0, but
        // such a pair is tangent to the surface and has no measure; keep it finite.
        tan_beta = abs_co > 0 ? sin_o / abs_co : 0.0;
      }
      return r * (kInvPi * (on_a + on_b * max_cos * sin_alpha * tan_beta));
    }
    case LobeType::Microfacet: {
      double co = std::abs(wo.z), ci = std::abs(wi.z);
      if (ci == 0 || co == 0) return {};
      Vec3 h = wi + wo;
      double h_length = length(h);
      if (!(h_length > 0)) return {};
      h /= h_length;
      double cos_h = dot(wi, h.z < 0 ? -h : h);
      Rgb fresnel = this->fresnel == FresnelType::Conductor
                        ? fresnel_conductor(cos_h, eta, k)
                        : Rgb(1, 1, 1) * fresnel_dielectric(cos_h, eta_i, eta_t);
      double microfacet = distribution.d(h) * distribution.g_over_cos_cos(wo, wi) * 0.25;
      return r * fresnel * microfacet;
    }
    case LobeType::FresnelBlend: {
      Rgb diffuse =
          (28.0 / (23.0 * kPi)) * r * (Rgb(1, 1, 1) - rs) *
          ((1.0 - pow5(1.0 - 0.5 * std::abs(wi.z))) * (1.0 - pow5(1.0 - 0.5 * std::abs(wo.z))));
      Vec3 h = wi + wo;
      double h_length = length(h);
      if (!(h_length > 0)) return {};
      h /= h_length;
      double wi_h = std::abs(dot(wi, h));
      double denominator = 4.0 * wi_h * std::max(std::abs(wi.z), std::abs(wo.z));
      if (!(denominator > 0)) return diffuse;
      double schlick_weight = pow5(1.0 - dot(wi, h));
      Rgb schlick = rs + schlick_weight * (Rgb(1, 1, 1) - rs);
      return diffuse + schlick * (distribution.d(h) / denominator);
    }
    default:
      return {};
  }
}

double BsdfLobe::pdf(const Vec3& wo, const Vec3& wi) const {
  if (!same_hemisphere(wo, wi)) return 0;
  auto microfacet_pdf = [&]() {
    Vec3 h = normalize(wo + wi);
    double wo_h = dot(wo, h);
    if (!(wo_h > 0)) return 0.0;
    return distribution.visible_normal_pdf(wo, h) / (4.0 * wo_h);
  };
  switch (type) {
    case LobeType::Lambert:
    case LobeType::OrenNayar:
      return std::abs(wi.z) * kInvPi;
    case LobeType::Microfacet:
      return microfacet_pdf();
    case LobeType::FresnelBlend:
      return 0.5 * (std::abs(wi.z) * kInvPi + microfacet_pdf());
    default:
      return 0;
  }
}

std::optional<Vec3> BsdfLobe::sample(const Vec3& wo, const Vec2& u_in) const {
  if (wo.z == 0) return std::nullopt;
  Vec2 u = u_in;
  auto cosine = [&](const Vec2& v) {
    Vec3 wi = sample_cosine_hemisphere(v);
    if (wo.z < 0) wi.z = -wi.z;
    return wi;
  };
  auto reflected = [&](const Vec2& v) -> std::optional<Vec3> {
    Vec3 h = distribution.sample_visible_normal(wo, v);
    double wo_h = dot(wo, h);
    if (!(wo_h > 0)) return std::nullopt;
    Vec3 wi = 2.0 * wo_h * h - wo;
    if (!same_hemisphere(wo, wi)) return std::nullopt;
    return wi;
  };
  switch (type) {
    case LobeType::Lambert:
    case LobeType::OrenNayar:
      return cosine(u);
    case LobeType::Microfacet:
      return reflected(u);
    case LobeType::FresnelBlend:
      if (u.x < 0.5) return cosine({std::min(2.0 * u.x, kOneMinusEpsilon), u.y});
      return reflected({std::min(2.0 * (u.x - 0.5), kOneMinusEpsilon), u.y});
    default:
      return std::nullopt;
  }
}

SurfaceBsdf::SurfaceBsdf(const Frame& shading, const Vec3& geometric_normal)
    : shading_(shading), ng_(geometric_normal) {
  defensive_ = std::abs(dot(shading.n, geometric_normal)) < 1.0 - 1e-12;
}

void SurfaceBsdf::add(const BsdfLobe& lobe) {
  if (count_ >= kMaxLobes) return;
  lobes_[count_] = lobe;
  if (!lobe.is_delta()) {
    weights_[count_] = sampling_weight(lobe);
    non_delta_weight_ += weights_[count_];
    ++non_delta_count_;
  }
  ++count_;
}

bool SurfaceBsdf::reflects(const Vec3& wo, const Vec3& wi) const {
  return dot(wo, ng_) * dot(wi, ng_) > 0;
}

Rgb SurfaceBsdf::f(const Vec3& wo, const Vec3& wi) const {
  if (non_delta_count_ == 0 || !reflects(wo, wi)) return {};
  Vec3 wo_local = shading_.to_local(wo), wi_local = shading_.to_local(wi);
  if (wo_local.z == 0) return {};
  Rgb sum;
  for (int i = 0; i < count_; ++i)
    if (!lobes_[i].is_delta()) sum += lobes_[i].f(wo_local, wi_local);
  return clamp_finite(sum);
}

Rgb SurfaceBsdf::f_for_geometric_cosine(const Vec3& wo, const Vec3& wi) const {
  double cos_g = std::abs(dot(ng_, wi));
  if (!(cos_g > 0)) return {};
  Rgb value = f(wo, wi);
  if (!defensive_) return value;  // shading normal = geometric normal: the ratio is 1
  Rgb scaled = value * (std::abs(dot(shading_.n, wi)) / cos_g);
  return clamp_finite(scaled);
}

double SurfaceBsdf::pdf(const Vec3& wo, const Vec3& wi) const {
  if (non_delta_count_ == 0 || !reflects(wo, wi)) return 0;
  Vec3 wo_local = shading_.to_local(wo), wi_local = shading_.to_local(wi);
  double mixture = 0;
  if (wo_local.z != 0) {
    for (int i = 0; i < count_; ++i) {
      if (lobes_[i].is_delta()) continue;
      double p = weights_[i] / non_delta_weight_;
      if (p > 0) mixture += p * lobes_[i].pdf(wo_local, wi_local);
    }
  }
  if (defensive_) {
    double defensive = std::abs(dot(ng_, wi)) * kInvPi;
    mixture = (1.0 - kDefensiveFraction) * mixture + kDefensiveFraction * defensive;
  }
  return std::isfinite(mixture) ? mixture : 0.0;
}

std::optional<SurfaceBsdf::Sample> SurfaceBsdf::sample(const Vec3& wo, const Vec2& u_in) const {
  if (non_delta_count_ == 0) return std::nullopt;
  Vec2 u{std::clamp(u_in.x, 0.0, kOneMinusEpsilon), std::clamp(u_in.y, 0.0, kOneMinusEpsilon)};
  Vec3 wi;
  if (defensive_ && u.x < kDefensiveFraction) {
    // Cosine about the geometric normal, on wo's side.
    Vec2 v{std::min(u.x / kDefensiveFraction, kOneMinusEpsilon), u.y};
    Vec3 ng = dot(ng_, wo) < 0 ? -ng_ : ng_;
    wi = Frame::from_normal(ng).to_world(sample_cosine_hemisphere(v));
  } else {
    if (defensive_)
      u.x = std::min((u.x - kDefensiveFraction) / (1.0 - kDefensiveFraction), kOneMinusEpsilon);
    // Choose a lobe by weight, reusing u.x.
    int chosen = -1;
    double begin = 0, width = 0;
    for (int i = 0; i < count_; ++i) {
      if (lobes_[i].is_delta()) continue;
      double p = weights_[i] / non_delta_weight_;
      if (!(p > 0)) continue;
      chosen = i;
      width = p;
      if (u.x < begin + p) break;
      begin += p;
    }
    if (chosen < 0) return std::nullopt;
    Vec2 v{std::clamp((u.x - begin) / width, 0.0, kOneMinusEpsilon), u.y};
    Vec3 wo_local = shading_.to_local(wo);
    std::optional<Vec3> local = lobes_[chosen].sample(wo_local, v);
    if (!local) return std::nullopt;
    wi = shading_.to_world(*local);
  }
  double length_wi = length(wi);
  if (!(length_wi > 0) || !std::isfinite(length_wi)) return std::nullopt;
  wi /= length_wi;
  if (!reflects(wo, wi)) return std::nullopt;
  double density = pdf(wo, wi);
  if (!(density > 0) || !std::isfinite(density)) return std::nullopt;
  return Sample{wi, density};
}

int SurfaceBsdf::specular_branches(const Vec3& wo, SpecularBranch out[kMaxLobes]) const {
  int n = 0;
  Vec3 wo_local = shading_.to_local(wo);
  if (wo_local.z == 0) return 0;
  for (int i = 0; i < count_; ++i) {
    const BsdfLobe& lobe = lobes_[i];
    if (lobe.type == LobeType::SpecularReflection) {
      Vec3 wi_local{-wo_local.x, -wo_local.y, wo_local.z};
      double fresnel = lobe.fresnel == FresnelType::Dielectric
                           ? fresnel_dielectric(wi_local.z, lobe.eta_i, lobe.eta_t)
                           : 1.0;
      Rgb weight = clamp_finite(lobe.r * fresnel);
      if (!is_black(weight)) out[n++] = {normalize(shading_.to_world(wi_local)), weight};
    } else if (lobe.type == LobeType::SpecularTransmission) {
      bool entering = wo_local.z > 0;
      double eta_incident = entering ? lobe.eta_i : lobe.eta_t;
      double eta_transmitted = entering ? lobe.eta_t : lobe.eta_i;
      Vec3 n_wo{0, 0, entering ? 1.0 : -1.0};
      std::optional<Vec3> wi_local = refract(wo_local, n_wo, eta_incident / eta_transmitted);
      if (!wi_local || wi_local->z == 0) continue;
      double fresnel = fresnel_dielectric(wi_local->z, lobe.eta_i, lobe.eta_t);
      double ratio = eta_incident / eta_transmitted;
      Rgb weight = clamp_finite(lobe.r * ((1.0 - fresnel) * ratio * ratio));
      if (!is_black(weight)) out[n++] = {normalize(shading_.to_world(*wi_local)), weight};
    }
  }
  return n;
}

}  // namespace penumbra
