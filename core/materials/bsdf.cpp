// The three materials of SCENE_FORMAT.md: evaluation, importance sampling and its density.
//
// lambert: f = albedo / pi; cosine-weighted sampling.
// phong:   f = kd / pi + ks (n + 2) / (2 pi) max(0, R.wi)^n, R the mirror of wo about the normal
//          (Billen & Dutre 2016 Eq. 9). Sampling picks the diffuse lobe (cosine) or the specular
//          lobe (density (n + 1) / (2 pi) cos^n around R) in proportion to the luminance of kd and
//          ks; the density is the mixture.
// ggx:     f = diffuse / pi + D G2 F / (4 cos_o cos_i) (core/materials/ggx.h), alpha = roughness
//          clamped to at least 1e-4. Sampling picks the cosine lobe or GGX visible-normal
//          sampling (Heitz 2018) in proportion to the luminance of diffuse and F0 (specular).
//
// A sample that falls below the horizon is a failed sample (empty), and the density returned by
// pdf_bsdf is the full mixture density (not renormalized over the returned samples), so
// f cos / pdf stays an unbiased estimator. When wo is not strictly above the surface f is 0
// everywhere, sampling fails and the density is 0.

#include "core/materials/bsdf.h"

#include "core/materials/ggx.h"

namespace penumbra {
namespace {

Vec3 reflect_about(const Vec3& w, const Vec3& axis) {
  return 2.0 * dot(w, axis) * axis - w;
}

// Cosine-weighted direction around +z (polar map of the unit disk, projected up).
Vec3 sample_cosine_hemisphere(const Vec2& u) {
  double r = std::sqrt(u.x);
  double phi = 2.0 * kPi * u.y;
  return {r * std::cos(phi), r * std::sin(phi), safe_sqrt(1.0 - u.x)};
}

// Probability of choosing the first of two lobes, by luminance (the first when both are black).
double first_lobe_probability(const Rgb& first, const Rgb& second) {
  double a = std::max(0.0, luminance(first)), b = std::max(0.0, luminance(second));
  if (!(a + b > 0)) return 1.0;
  return a / (a + b);
}

// Reuses the random number that chose a lobe: maps [begin, begin + width) back to [0, 1).
double remap_after_choice(double u, double begin, double width) {
  return std::clamp((u - begin) / width, 0.0, 0x1.fffffffffffffp-1);
}

double ggx_alpha(const Material& m) {
  return std::max(kGgxMinAlpha, m.roughness);
}
double phong_exponent(const Material& m) {
  return std::max(0.0, m.exponent);
}

// Density of the Phong specular lobe (n + 1) / (2 pi) cos^n around R; 0 where cos <= 0.
double phong_lobe_pdf(double cos_alpha, double exponent) {
  if (!(cos_alpha > 0)) return 0;
  return (exponent + 1.0) / (2.0 * kPi) * std::pow(std::min(1.0, cos_alpha), exponent);
}

// The mixture density in solid angle, given both cosines are known to be positive.
double mixture_pdf(const Material& m, const Vec3& n, const Vec3& wo, const Vec3& wi, double cos_i) {
  switch (m.type) {
    case MaterialType::Lambert:
      return cos_i * kInvPi;
    case MaterialType::Phong: {
      double p_diffuse = first_lobe_probability(m.kd, m.ks);
      Vec3 mirror = reflect_about(wo, n);
      return p_diffuse * cos_i * kInvPi +
             (1.0 - p_diffuse) * phong_lobe_pdf(dot(mirror, wi), phong_exponent(m));
    }
    case MaterialType::Ggx: {
      double p_diffuse = first_lobe_probability(m.diffuse, m.specular);
      Frame frame = Frame::from_normal(n);
      double specular =
          p_diffuse < 1.0 ? ggx_reflection_pdf(frame.to_local(wo), frame.to_local(wi), ggx_alpha(m))
                          : 0.0;
      return p_diffuse * cos_i * kInvPi + (1.0 - p_diffuse) * specular;
    }
    default:  // the pbrt-v3 materials: core/materials/surface_bsdf.h
      break;
  }
  return 0;
}

}  // namespace

Rgb eval_bsdf(const Material& m, const Vec3& n, const Vec3& wo, const Vec3& wi) {
  double cos_o = dot(n, wo), cos_i = dot(n, wi);
  if (!(cos_o > 0) || !(cos_i > 0)) return {0, 0, 0};
  switch (m.type) {
    case MaterialType::Lambert:
      return m.albedo * kInvPi;
    case MaterialType::Phong: {
      double exponent = phong_exponent(m);
      double cos_alpha = std::clamp(dot(reflect_about(wo, n), wi), 0.0, 1.0);
      double lobe =
          cos_alpha > 0 ? (exponent + 2.0) / (2.0 * kPi) * std::pow(cos_alpha, exponent) : 0.0;
      return m.kd * kInvPi + m.ks * lobe;
    }
    case MaterialType::Ggx: {
      Frame frame = Frame::from_normal(n);
      Vec3 wo_local = frame.to_local(wo), wi_local = frame.to_local(wi);
      double microfacet = ggx_specular_without_fresnel(wo_local, wi_local, ggx_alpha(m));
      Rgb fresnel{0, 0, 0};
      if (microfacet > 0) {
        Vec3 h = normalize(wo + wi);
        fresnel = schlick_fresnel(m.specular, dot(wi, h));
      }
      return m.diffuse * kInvPi + fresnel * microfacet;
    }
    default:
      break;
  }
  return {0, 0, 0};
}

std::optional<BsdfSample> sample_bsdf(const Material& m, const Vec3& n, const Vec3& wo,
                                      const Vec2& u_in) {
  if (!(dot(n, wo) > 0)) return std::nullopt;
  Vec2 u{std::clamp(u_in.x, 0.0, 0x1.fffffffffffffp-1),
         std::clamp(u_in.y, 0.0, 0x1.fffffffffffffp-1)};
  Frame frame = Frame::from_normal(n);
  Vec3 wi;
  switch (m.type) {
    case MaterialType::Lambert:
      wi = frame.to_world(sample_cosine_hemisphere(u));
      break;
    case MaterialType::Phong: {
      double p_diffuse = first_lobe_probability(m.kd, m.ks);
      if (u.x < p_diffuse) {
        Vec2 v{remap_after_choice(u.x, 0.0, p_diffuse), u.y};
        wi = frame.to_world(sample_cosine_hemisphere(v));
      } else {
        // Specular lobe: cos(alpha) = v^(1/(n+1)) around R; 1 - cos from expm1 keeps precision
        // for exponents up to 1e4 and beyond.
        double v = remap_after_choice(u.x, p_diffuse, 1.0 - p_diffuse);
        double one_minus_cos = -std::expm1(std::log(v) / (phong_exponent(m) + 1.0));
        one_minus_cos = std::clamp(one_minus_cos, 0.0, 1.0);
        double cos_alpha = 1.0 - one_minus_cos;
        double sin_alpha = safe_sqrt(one_minus_cos * (2.0 - one_minus_cos));
        double phi = 2.0 * kPi * u.y;
        Frame lobe = Frame::from_normal(normalize(reflect_about(wo, n)));
        wi = lobe.to_world({sin_alpha * std::cos(phi), sin_alpha * std::sin(phi), cos_alpha});
      }
      break;
    }
    case MaterialType::Ggx: {
      double p_diffuse = first_lobe_probability(m.diffuse, m.specular);
      if (u.x < p_diffuse) {
        Vec2 v{remap_after_choice(u.x, 0.0, p_diffuse), u.y};
        wi = frame.to_world(sample_cosine_hemisphere(v));
      } else {
        Vec2 v{remap_after_choice(u.x, p_diffuse, 1.0 - p_diffuse), u.y};
        Vec3 wo_local = frame.to_local(wo);
        Vec3 h = sample_ggx_visible_normal(wo_local, ggx_alpha(m), v);
        wi = frame.to_world(reflect_about(wo_local, h));
      }
      break;
    }
    default:
      return std::nullopt;
  }
  double length_wi = length(wi);
  if (!(length_wi > 0) || !std::isfinite(length_wi)) return std::nullopt;
  wi /= length_wi;
  double cos_i = dot(n, wi);
  if (!(cos_i > 0)) return std::nullopt;  // below the horizon: a failed sample
  double pdf = mixture_pdf(m, n, wo, wi, cos_i);
  if (!(pdf > 0) || !std::isfinite(pdf)) return std::nullopt;
  return BsdfSample{wi, pdf};
}

double pdf_bsdf(const Material& m, const Vec3& n, const Vec3& wo, const Vec3& wi) {
  double cos_o = dot(n, wo), cos_i = dot(n, wi);
  if (!(cos_o > 0) || !(cos_i > 0)) return 0;
  double pdf = mixture_pdf(m, n, wo, wi, cos_i);
  return std::isfinite(pdf) ? pdf : 0;
}

}  // namespace penumbra
