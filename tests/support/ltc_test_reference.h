#pragma once
// Reference pieces for the LTC tests: the `ggx` specular lobe written out again from its
// definition (Heitz 2014: GGX D, height-correlated Smith G2, Schlick F), independently of
// core/materials (which the tests of core/math do not link), and quadrature over the hemisphere.

#include <cmath>
#include <functional>

#include "core/math/vec.h"

namespace penumbra::ltc_test {

inline double ggx_d(const Vec3& h, double alpha) {
  double a2 = alpha * alpha;
  double t = h.z * h.z * (a2 - 1.0) + 1.0;
  return a2 / (kPi * t * t);
}

inline double ggx_lambda(double cos_theta, double alpha) {
  double cos2 = cos_theta * cos_theta;
  double tan2 = (1.0 - cos2) / cos2;
  return 0.5 * (std::sqrt(1.0 + alpha * alpha * tan2) - 1.0);
}

// f_spec(wo, wi) cos(theta_i) with F = 1: D G2 / (4 cos_o cos_i) cos_i; 0 below the horizon.
inline double ggx_lobe_times_cosine(const Vec3& wo, const Vec3& wi, double alpha) {
  if (!(wo.z > 0) || !(wi.z > 0)) return 0;
  Vec3 h = normalize(wo + wi);
  double g2 = 1.0 / (1.0 + ggx_lambda(wo.z, alpha) + ggx_lambda(wi.z, alpha));
  return ggx_d(h, alpha) * g2 / (4.0 * wo.z);
}

inline double schlick_weight(const Vec3& wo, const Vec3& wi) {
  Vec3 h = normalize(wo + wi);
  return std::pow(std::clamp(1.0 - dot(wi, h), 0.0, 1.0), 5.0);
}

// Integral of f over the sphere by the midpoint rule in (cos theta, phi), with extra resolution
// near the direction `focus` (the rule runs in a frame around it).
inline double integrate_sphere(const std::function<double(const Vec3&)>& f, const Vec3& focus,
                               int theta_steps, int phi_steps) {
  Frame frame = Frame::from_normal(normalize(focus));
  // theta = pi t^2 concentrates the nodes near the focus; d(omega) = sin(theta) 2 pi t dt dphi.
  double total = 0;
  for (int i = 0; i < theta_steps; ++i) {
    double t = (i + 0.5) / theta_steps;
    double theta = kPi * t * t;
    double weight = std::sin(theta) * 2.0 * kPi * t / theta_steps * (2.0 * kPi / phi_steps);
    for (int k = 0; k < phi_steps; ++k) {
      double phi = 2.0 * kPi * (k + 0.5) / phi_steps;
      Vec3 local{std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
      total += f(frame.to_world(local)) * weight;
    }
  }
  return total;
}

}  // namespace penumbra::ltc_test
