#include "core/lines/line_integrals.h"

#include <algorithm>
#include <cmath>

namespace penumbra {

namespace {

constexpr double kHalfPi = 0.5 * kPi;

// 8-point Gauss-Legendre nodes and weights on [-1, 1].
constexpr double kGaussNodes[4] = {0.1834346424956498, 0.5255324099163290, 0.7966664774136267,
                                   0.9602898564975363};
constexpr double kGaussWeights[4] = {0.3626837833783620, 0.3137066458778873, 0.2223810344533745,
                                     0.1012285362903763};

// The continued fraction of the incomplete beta function, evaluated by the modified Lentz
// method: B_x(a, b) = x^a (1-x)^b / a * fraction. Converges fast for x < (a+1)/(a+b+2).
double beta_continued_fraction(double a, double b, double x) {
  constexpr double kTiny = 1e-300;
  constexpr double kEpsilon = 1e-16;
  double c = 1.0;
  double d = 1.0 - (a + b) * x / (a + 1.0);
  if (std::abs(d) < kTiny) d = kTiny;
  d = 1.0 / d;
  double result = d;
  for (int m = 1; m <= 20000; ++m) {
    double m2 = 2.0 * m;
    // Even step: d_{2m} = m (b - m) x / ((a + 2m - 1)(a + 2m)).
    double coefficient = m * (b - m) * x / ((a + m2 - 1.0) * (a + m2));
    d = 1.0 + coefficient * d;
    if (std::abs(d) < kTiny) d = kTiny;
    c = 1.0 + coefficient / c;
    if (std::abs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    result *= d * c;
    // Odd step: d_{2m+1} = -(a + m)(a + b + m) x / ((a + 2m)(a + 2m + 1)).
    coefficient = -(a + m) * (a + b + m) * x / ((a + m2) * (a + m2 + 1.0));
    d = 1.0 + coefficient * d;
    if (std::abs(d) < kTiny) d = kTiny;
    c = 1.0 + coefficient / c;
    if (std::abs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    double step = d * c;
    result *= step;
    if (std::abs(step - 1.0) < kEpsilon) break;
  }
  return result;
}

// integral_0^{pi/2} cos^k = (1/2) B((k+1)/2, 1/2). A shading point asks for the same two
// exponents (m and m+2) many times: the last few are cached per thread (lgamma is slow).
double half_cosine_power_integral(double k) {
  struct Entry {
    double k = -1, value = 0;
  };
  thread_local Entry cache[2];
  for (const Entry& entry : cache) {
    if (entry.k == k) return entry.value;
  }
  double a = 0.5 * (k + 1.0);
  double value = 0.5 * std::exp(std::lgamma(a) + std::lgamma(0.5) - std::lgamma(a + 0.5));
  cache[1] = cache[0];
  cache[0] = {k, value};
  return value;
}

// Both halves of [0, pi/2] split at w: head = integral_0^w cos^k, tail = integral_w^{pi/2}
// cos^k, each with its own relative precision. With x = cos^2 w, a = (k+1)/2:
//   tail = (1/2) B_x(a, 1/2) = cos^{k+1} w sin w / (k+1) * CF(a, 1/2, x),
//   head = (1/2) B_{1-x}(1/2, a) = sin w cos^{k+1} w * CF(1/2, a, 1-x);
// the one whose fraction converges is evaluated directly, the other as the full half minus it
// (then it is the larger one: no cancellation).
struct CosinePowerHalves {
  double head = 0, tail = 0;
};
CosinePowerHalves cosine_power_halves(double k, double w) {
  w = std::clamp(w, 0.0, kHalfPi);
  double cos_w = std::cos(w), sin_w = std::sin(w);
  double a = 0.5 * (k + 1.0);
  double x = cos_w * cos_w;
  double full = half_cosine_power_integral(k);
  double common = std::pow(cos_w, k + 1.0) * sin_w;
  CosinePowerHalves halves;
  if (x < (a + 1.0) / (a + 2.5)) {
    halves.tail = common / (k + 1.0) * beta_continued_fraction(a, 0.5, x);
    halves.head = std::max(0.0, full - halves.tail);
  } else {
    halves.head = common * beta_continued_fraction(0.5, a, sin_w * sin_w);
    halves.tail = std::max(0.0, full - halves.head);
  }
  return halves;
}

// integral_0^w cos^k for integer k by Billen & Dutré's Eq. 16 (Appendix B):
// G_k = cos^{k-1}(w) sin(w) / k + (k-1)/k G_{k-2}, G_0 = w, G_1 = sin w. For w in [0, pi/2]
// every term is non-negative, so the forward recursion loses no precision.
double cosine_power_head_recursive(int k, double w) {
  double cos_w = std::cos(w), sin_w = std::sin(w);
  double value = (k % 2 == 0) ? w : sin_w;
  // cos^{j-1} for j = start + 2, start + 4, ...
  double cos_power = (k % 2 == 0) ? cos_w : cos_w * cos_w;
  for (int j = (k % 2 == 0) ? 2 : 3; j <= k; j += 2) {
    value = cos_power * sin_w / j + (j - 1.0) / j * value;
    cos_power *= cos_w * cos_w;
  }
  return value;
}

bool is_small_integer(double k) {
  return k <= kPhongRecursionMaxExponent && k == std::floor(k);
}

// integral of cos^k over [0, w], w in [0, pi/2].
double cosine_power_head(double k, double w) {
  if (is_small_integer(k)) return cosine_power_head_recursive(static_cast<int>(k), w);
  return cosine_power_halves(k, w).head;
}

// integral of cos^k over [u0, u1] with 0 <= u0 <= u1 <= pi/2: the difference of the two heads
// or of the two tails, whichever subtracts the smaller numbers.
double cosine_power_one_sided(double k, double u0, double u1) {
  CosinePowerHalves lower = cosine_power_halves(k, u0);
  CosinePowerHalves upper = cosine_power_halves(k, u1);
  double from_tails = lower.tail - upper.tail;
  double from_heads = upper.head - lower.head;
  return std::max(0.0, lower.tail < upper.head ? from_tails : from_heads);
}

}  // namespace

double cosine_power_integral(double k, double u0, double u1) {
  u0 = std::clamp(u0, -kHalfPi, kHalfPi);
  u1 = std::clamp(u1, -kHalfPi, kHalfPi);
  if (!(u0 < u1)) return 0;
  if (u0 < 0 && u1 > 0) return cosine_power_head(k, -u0) + cosine_power_head(k, u1);
  if (u0 >= 0) return cosine_power_one_sided(k, u0, u1);
  return cosine_power_one_sided(k, -u1, -u0);
}

LineReceiver make_line_receiver(const Material& material, const Vec3& x, const Vec3& n,
                                const Vec3& wo) {
  LineReceiver receiver;
  receiver.x = x;
  receiver.n = n;
  receiver.mirror = 2.0 * dot(wo, n) * n - wo;
  if (material.type == MaterialType::Phong) {
    receiver.diffuse = material.kd * kInvPi;
    receiver.exponent = std::max(0.0, material.exponent);
    receiver.specular = material.ks * ((receiver.exponent + 2.0) / (2.0 * kPi));
    receiver.has_specular = !is_black(material.ks);
  } else {
    receiver.diffuse = material.albedo * kInvPi;
  }
  return receiver;
}

LineIntegrator::LineIntegrator(const LineReceiver& receiver, const Vec3& a, const Vec3& b,
                               const Vec3& light_normal)
    : receiver_(&receiver) {
  Vec3 to_a = a - receiver.x;
  Vec3 to_b = b - receiver.x;
  Vec3 direction = b - a;
  double segment_length = length(direction);
  if (!(segment_length > 0) || !std::isfinite(segment_length) || !is_finite(to_a)) return;
  Vec3 e = direction / segment_length;
  // Height of x above the light's plane: only the emitting side receives anything.
  double height = -dot(light_normal, to_a);
  if (!(height > 0)) return;
  Vec3 perpendicular = cross_accurate(to_a, e);  // |.| = h
  h_ = length(perpendicular);
  if (!(h_ > 0)) return;
  Vec3 foot_direction = cross_accurate(e, perpendicular) / h_;  // c_hat
  s_a_ = dot(to_a, e);
  s_b_ = dot(to_b, e);
  prefactor_ = height / (h_ * h_);
  if (!std::isfinite(prefactor_) || !(prefactor_ > 0)) return;
  double n_c = dot(receiver.n, foot_direction), n_e = dot(receiver.n, e);
  normal_scale_ = std::hypot(n_c, n_e);
  if (!(normal_scale_ > 0)) return;
  theta_n_ = std::atan2(n_e, n_c);
  double r_c = dot(receiver.mirror, foot_direction), r_e = dot(receiver.mirror, e);
  mirror_scale_ = std::min(1.0, std::hypot(r_c, r_e));
  theta_r_ = std::atan2(r_e, r_c);
  zero_ = false;
}

double LineIntegrator::theta_at(double t) const {
  return std::atan2(s_a_ + t * (s_b_ - s_a_), h_);
}

double LineIntegrator::diffuse(double t0, double t1) const {
  if (zero_ || !(t0 < t1)) return 0;
  double theta0 = theta_at(t0), theta1 = theta_at(t1);
  double lo = std::max(theta0, theta_n_ - kHalfPi);
  double hi = std::min(theta1, theta_n_ + kHalfPi);
  if (!(lo < hi)) return 0;
  double width;
  if (lo == theta0 && hi == theta1) {
    // Unclipped: the angle subtended, without subtracting two nearly equal angles.
    double s0 = s_a_ + t0 * (s_b_ - s_a_), s1 = s_a_ + t1 * (s_b_ - s_a_);
    width = std::atan2((s1 - s0) * h_, h_ * h_ + s0 * s1);
    if (width < 0) width += 2.0 * kPi;  // cannot happen for theta in (-pi/2, pi/2); guard
  } else {
    width = hi - lo;
  }
  // (1/2) [width cos(theta_n) + cos(lo + hi - theta_n) sin(width)]  (Appendix A, re-derived).
  double integral =
      0.5 * (width * std::cos(theta_n_) + std::cos(lo + hi - theta_n_) * std::sin(width));
  return std::max(0.0, prefactor_ * normal_scale_ * integral);
}

double LineIntegrator::specular(double t0, double t1) const {
  if (zero_ || !(t0 < t1) || !receiver_->has_specular || !(mirror_scale_ > 0)) return 0;
  double m = receiver_->exponent;
  double theta0 = theta_at(t0), theta1 = theta_at(t1);
  double lo = std::max({theta0, theta_n_ - kHalfPi, theta_r_ - kHalfPi});
  double hi = std::min({theta1, theta_n_ + kHalfPi, theta_r_ + kHalfPi});
  if (!(lo < hi)) return 0;
  double lobe_scale = std::pow(mirror_scale_, m);
  if (!(lobe_scale > 0)) return 0;
  double u0 = std::clamp(lo - theta_r_, -kHalfPi, kHalfPi);
  double u1 = std::clamp(hi - theta_r_, -kHalfPi, kHalfPi);
  double shift_n = theta_r_ - theta_n_;  // A
  double shift_0 = theta_r_;             // B
  // How fast log(cos^m u) changes across the interval: small enough and the integrand is a
  // low-degree polynomial to double precision, so Gauss-Legendre is exact.
  double width = u1 - u0;
  double max_tan = std::max(std::abs(std::tan(u0)), std::abs(std::tan(u1)));
  double variation = width * (std::sqrt(m + 2.0) + m * max_tan);
  double integral;
  if (variation < 0.5) {
    double centre = 0.5 * (u0 + u1), half = 0.5 * width;
    integral = 0;
    for (int i = 0; i < 4; ++i) {
      for (double sign : {-1.0, 1.0}) {
        double u = centre + sign * half * kGaussNodes[i];
        double value = std::pow(std::max(0.0, std::cos(u)), m) *
                       std::max(0.0, std::cos(u + shift_n)) * std::max(0.0, std::cos(u + shift_0));
        integral += kGaussWeights[i] * value;
      }
    }
    integral *= half;
  } else {
    double c_m = cosine_power_integral(m, u0, u1);
    double c_m2 = cosine_power_integral(m + 2.0, u0, u1);
    // S_{m+1} = integral cos^{m+1} sin = [cos^{m+2}(u0) - cos^{m+2}(u1)] / (m+2)  (Eq. 15).
    double s_m1 = (std::pow(std::cos(u0), m + 2.0) - std::pow(std::cos(u1), m + 2.0)) / (m + 2.0);
    integral = std::cos(shift_n + shift_0) * c_m2 + std::sin(shift_n) * std::sin(shift_0) * c_m -
               std::sin(shift_n + shift_0) * s_m1;
  }
  return std::max(0.0, prefactor_ * normal_scale_ * lobe_scale * integral);
}

Rgb LineIntegrator::radiance(const Rgb& emitted, double t0, double t1) const {
  if (zero_) return {0, 0, 0};
  Rgb value = receiver_->diffuse * diffuse(t0, t1);
  if (receiver_->has_specular) value += receiver_->specular * specular(t0, t1);
  return emitted * value;
}

}  // namespace penumbra
