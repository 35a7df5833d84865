#include "core/materials/microfacet.h"

#include <algorithm>
#include <cmath>

#include "core/materials/ggx.h"

namespace penumbra {

double pbrt_roughness_to_alpha(double roughness) {
  double x = std::log(std::max(roughness, 1e-3));
  return 1.62142 + 0.819955 * x + 0.1734 * x * x + 0.0171201 * x * x * x +
         0.000640711 * x * x * x * x;
}

TrowbridgeReitz TrowbridgeReitz::make(double alpha_x, double alpha_y) {
  TrowbridgeReitz tr;
  // std::max(min, NaN) keeps min: a NaN roughness becomes the smoothest distribution.
  tr.alpha_x = std::max(kTrowbridgeReitzMinAlpha, alpha_x);
  tr.alpha_y = std::max(kTrowbridgeReitzMinAlpha, alpha_y);
  if (!std::isfinite(tr.alpha_x)) tr.alpha_x = kTrowbridgeReitzMinAlpha;
  if (!std::isfinite(tr.alpha_y)) tr.alpha_y = kTrowbridgeReitzMinAlpha;
  return tr;
}

double TrowbridgeReitz::d(const Vec3& h) const {
  double x = h.x / alpha_x, y = h.y / alpha_y;
  double e = x * x + y * y + h.z * h.z;
  if (!(e > 0)) return 0;
  return 1.0 / (kPi * alpha_x * alpha_y * e * e);
}

double TrowbridgeReitz::cos_times_lambda(const Vec3& w) const {
  double c = std::abs(w.z);
  double a = alpha_x * alpha_x * w.x * w.x + alpha_y * alpha_y * w.y * w.y;
  double denominator = 2.0 * (c + std::sqrt(c * c + a));
  return denominator > 0 ? a / denominator : 0.0;
}

double TrowbridgeReitz::g1_over_cos(const Vec3& w) const {
  double denominator = std::abs(w.z) + cos_times_lambda(w);
  return denominator > 0 ? 1.0 / denominator : 0.0;
}

double TrowbridgeReitz::g_over_cos_cos(const Vec3& wo, const Vec3& wi) const {
  double co = std::abs(wo.z), ci = std::abs(wi.z);
  // G / (co ci) = 1 / (co ci + ci (co Lambda_o) + co (ci Lambda_i)).
  double denominator = co * ci + ci * cos_times_lambda(wo) + co * cos_times_lambda(wi);
  return denominator > 0 ? 1.0 / denominator : 0.0;
}

Vec3 TrowbridgeReitz::sample_visible_normal(const Vec3& wo_in, const Vec2& u) const {
  // The sampler works on the upper hemisphere; a lower wo samples the mirrored lobe.
  bool flip = wo_in.z < 0;
  Vec3 h = sample_ggx_visible_normal(flip ? -wo_in : wo_in, alpha_x, alpha_y, u);
  return flip ? -h : h;
}

double TrowbridgeReitz::visible_normal_pdf(const Vec3& wo, const Vec3& h) const {
  double wo_h = dot(wo, h);
  // Only normals facing wo (on wo's side of the surface) are drawn.
  if (!(wo_h > 0) || !(h.z * wo.z > 0)) return 0;
  return g1_over_cos(wo) * wo_h * d(h);
}

double fresnel_dielectric(double cos_i, double eta_i, double eta_t) {
  cos_i = std::clamp(cos_i, -1.0, 1.0);
  if (cos_i < 0) {
    std::swap(eta_i, eta_t);
    cos_i = -cos_i;
  }
  double sin_i = safe_sqrt(1.0 - cos_i * cos_i);
  double sin_t = eta_i / eta_t * sin_i;
  if (!(sin_t < 1)) return 1.0;  // total internal reflection (and eta_t == 0)
  double cos_t = safe_sqrt(1.0 - sin_t * sin_t);
  double parallel = (eta_t * cos_i - eta_i * cos_t) / (eta_t * cos_i + eta_i * cos_t);
  double perpendicular = (eta_i * cos_i - eta_t * cos_t) / (eta_i * cos_i + eta_t * cos_t);
  double f = 0.5 * (parallel * parallel + perpendicular * perpendicular);
  return std::isfinite(f) ? f : 1.0;
}

Rgb fresnel_conductor(double cos_i, const Rgb& eta, const Rgb& k) {
  cos_i = std::min(1.0, std::abs(cos_i));
  double cos2 = cos_i * cos_i;
  double sin2 = 1.0 - cos2;
  Rgb result;
  for (int c = 0; c < 3; ++c) {
    double eta2 = eta[c] * eta[c], k2 = k[c] * k[c];
    double t0 = eta2 - k2 - sin2;
    double a2_plus_b2 = std::sqrt(t0 * t0 + 4.0 * eta2 * k2);
    double t1 = a2_plus_b2 + cos2;
    double a = safe_sqrt(0.5 * (a2_plus_b2 + t0));
    double t2 = 2.0 * cos_i * a;
    double rs = (t1 - t2) / (t1 + t2);
    double t3 = cos2 * a2_plus_b2 + sin2 * sin2;
    double t4 = t2 * sin2;
    double rp = rs * (t3 - t4) / (t3 + t4);
    double f = 0.5 * (rp + rs);
    result[c] = std::isfinite(f) ? std::clamp(f, 0.0, 1.0) : 1.0;
  }
  return result;
}

}  // namespace penumbra
