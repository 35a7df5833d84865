#include "core/materials/ggx.h"

namespace penumbra {

double ggx_distribution(const Vec3& h_local, double alpha) {
  double alpha_sq = alpha * alpha;
  // cos^2 (alpha^2 - 1) + 1 written as sin^2 + alpha^2 cos^2: no cancellation near h = n.
  double denominator =
      h_local.x * h_local.x + h_local.y * h_local.y + alpha_sq * h_local.z * h_local.z;
  if (!(denominator > 0)) return 0;
  return alpha_sq / (kPi * denominator * denominator);
}

double ggx_cos_times_lambda(double c, double alpha) {
  double sin_sq = std::max(0.0, (1.0 - c) * (1.0 + c));
  double a = alpha * alpha * sin_sq;
  return a / (2.0 * (c + std::sqrt(c * c + a)));
}

double ggx_g1_over_cos(double c, double alpha) {
  // 1 / (cos (1 + Lambda)) = 1 / (cos + cos Lambda).
  return 1.0 / (c + ggx_cos_times_lambda(c, alpha));
}

double ggx_specular_without_fresnel(const Vec3& wo_local, const Vec3& wi_local, double alpha) {
  double cos_o = wo_local.z, cos_i = wi_local.z;
  if (!(cos_o > 0) || !(cos_i > 0)) return 0;
  Vec3 h = wo_local + wi_local;
  double h_length = length(h);
  if (!(h_length > 0)) return 0;
  h /= h_length;
  // G2 / (cos_o cos_i) = 1 / (cos_o cos_i + cos_i (cos_o Lambda_o) + cos_o (cos_i Lambda_i)).
  double g2_denominator = cos_o * cos_i + cos_i * ggx_cos_times_lambda(cos_o, alpha) +
                          cos_o * ggx_cos_times_lambda(cos_i, alpha);
  if (!(g2_denominator > 0)) return 0;
  return ggx_distribution(h, alpha) / (4.0 * g2_denominator);
}

Rgb schlick_fresnel(const Rgb& f0, double cos_theta) {
  double m = std::clamp(1.0 - cos_theta, 0.0, 1.0);
  double m2 = m * m;
  double weight = m2 * m2 * m;
  return f0 + (Rgb{1, 1, 1} - f0) * weight;
}

Vec3 sample_ggx_visible_normal(const Vec3& wo_local, double alpha, const Vec2& u) {
  return sample_ggx_visible_normal(wo_local, alpha, alpha, u);
}

Vec3 sample_ggx_visible_normal(const Vec3& wo_local, double alpha_x, double alpha_y,
                               const Vec2& u) {
  // Heitz 2018, Listing 1. Stretch wo to the hemisphere configuration.
  Vec3 vh = normalize(Vec3{alpha_x * wo_local.x, alpha_y * wo_local.y, wo_local.z});
  // Orthonormal basis around vh (vh.z >= 0).
  double lensq = vh.x * vh.x + vh.y * vh.y;
  Vec3 t1 = lensq > 0 ? Vec3{-vh.y, vh.x, 0} / std::sqrt(lensq) : Vec3{1, 0, 0};
  Vec3 t2 = cross(vh, t1);
  // Uniform point on the disk, warped to the projected visible half of the hemisphere.
  double r = std::sqrt(u.x);
  double phi = 2.0 * kPi * u.y;
  double p1 = r * std::cos(phi);
  double p2 = r * std::sin(phi);
  double s = 0.5 * (1.0 + vh.z);
  p2 = (1.0 - s) * safe_sqrt(1.0 - p1 * p1) + s * p2;
  // Reproject onto the hemisphere and unstretch.
  Vec3 nh = p1 * t1 + p2 * t2 + safe_sqrt(1.0 - p1 * p1 - p2 * p2) * vh;
  Vec3 ne{alpha_x * nh.x, alpha_y * nh.y, std::max(0.0, nh.z)};
  double ne_length = length(ne);
  if (!(ne_length > 0)) return {0, 0, 1};
  return ne / ne_length;
}

double ggx_reflection_pdf(const Vec3& wo_local, const Vec3& wi_local, double alpha) {
  double cos_o = wo_local.z;
  if (!(cos_o > 0) || !(wi_local.z > 0)) return 0;
  Vec3 h = wo_local + wi_local;
  double h_length = length(h);
  if (!(h_length > 0)) return 0;
  h /= h_length;
  return 0.25 * ggx_g1_over_cos(cos_o, alpha) * ggx_distribution(h, alpha);
}

}  // namespace penumbra
