#pragma once
// Closed-form shading of a line segment on an area light (Billen & Dutré 2016 Sec. 5.3,
// Appendices A and B), re-derived here in an angle parametrization.
//
// Setting. x is the shading point (unit normal n), the segment is p(t) = a + t (b - a) on a
// light with unit emission normal nl and constant radiance Le. We want
//   I(t0, t1) = integral_{t0}^{t1} f(wo, wi) max(0, n.wi) cos_l / r^2 |b - a| dt,
// wi = (p - x) / r, r = |p - x|, cos_l = max(0, -nl.wi). Integrating I over the line's
// perpendicular offset gives the area integral of f G Le (so I is "per unit offset").
//
// Derivation (x at the origin). Let e = (b - a)/|b - a|, h the distance from x to the segment's
// line, c_hat the unit vector from x to the foot of the perpendicular, s the signed position
// along e from that foot. Substituting s = h tan(theta), theta in (-pi/2, pi/2):
//   wi = cos(theta) c_hat + sin(theta) e,  r = h / cos(theta),  ds / r^2 = dtheta / h,
//   cos_l = -nl.wi = -(nl.c_hat) cos(theta)   (nl.e = 0: the line lies in the light's plane).
// With q = -nl.(a - x) = h (-nl.c_hat) the height of x above the light's plane:
//   I = (q / h^2) integral f(theta) max(0, n.wi) cos(theta) dtheta.
// n.wi = n_c cos(theta) + n_e sin(theta) = N cos(theta - theta_n), N = |(n_c, n_e)|: the horizon
// of x clips theta to [theta_n - pi/2, theta_n + pi/2] (the part below counts zero, never |cos|).
//
// Lambert / Phong diffuse (Appendix A, re-derived): f = kd/pi, and
//   integral cos(theta - theta_n) cos(theta) dtheta
//     = (1/2) [dtheta cos(theta_n) + cos(theta0 + theta1 - theta_n) sin(dtheta)]
// with dtheta = theta1 - theta0 (written with the sum-to-product identity so that short
// segments do not cancel).
//
// Phong specular (Appendix B, re-derived): f = ks (m+2)/(2 pi) max(0, R.wi)^m, R the mirror of
// wo. R.wi = M cos(theta - theta_R). With u = theta - theta_R, A = theta_R - theta_n, B = theta_R:
//   cos^m(u) cos(u + A) cos(u + B)
//     = cos(A+B) cos^{m+2}(u) + sin(A) sin(B) cos^m(u) - sin(A+B) cos^{m+1}(u) sin(u),
// so the integral is M^m N [cos(A+B) C_{m+2} + sin A sin B C_m - sin(A+B) S_{m+1}] with
// S_k = integral cos^k sin = [-cos^{k+1}/(k+1)] (their Eq. 15) and C_k = integral cos^k (their
// Eq. 16, the recursion C_k = [cos^{k-1} sin]/k + (k-1)/k C_{k-2}).
//
// Numerics of C_k on [u0, u1] (u within [-pi/2, pi/2]):
// - an interval containing 0 is split at 0 and each half integral_0^w cos^k is summed by the
//   recursion of Eq. 16 for integer k <= kPhongRecursionMaxExponent (every term is positive:
//   no cancellation);
// - otherwise, and for large or fractional exponents (the fast path), C_k is an incomplete beta
//   function: integral_w^{pi/2} cos^k = (1/2) B(cos^2 w; (k+1)/2, 1/2) and
//   integral_0^w cos^k = (1/2) B(sin^2 w; 1/2, (k+1)/2), evaluated by the continued fraction of
//   the incomplete beta function (O(sqrt(k)) terms instead of k/2 recursion steps); one-sided
//   intervals are differences of upper tails, so the tiny values far from the lobe keep their
//   relative precision;
// - an interval narrower than a fraction of the lobe width (1/sqrt(m+2)) is integrated by
//   8-point Gauss-Legendre (the integrand is then a low-degree polynomial to double precision).
// Relative error against adaptive quadrature: below 1e-6 for exponents 0..10^4 (tests).
//
// Degenerate input (x on the light's plane or behind it, x on the segment's line, zero-length
// segment, non-finite values) integrates to 0.

#include "core/math/vec.h"
#include "core/scene/scene.h"

namespace penumbra {

// Integer Phong exponents up to this use the recursion of Eq. 16 on intervals around the lobe.
inline constexpr int kPhongRecursionMaxExponent = 256;

// The receiver side of the line integrals: what the shading point and its material contribute.
struct LineReceiver {
  Vec3 x;                 // shading point
  Vec3 n;                 // unit shading normal (on the side of wo)
  Vec3 mirror;            // wo mirrored about n (Phong lobe axis)
  Rgb diffuse{0, 0, 0};   // constant BRDF part: albedo/pi (lambert) or kd/pi (phong)
  Rgb specular{0, 0, 0};  // ks (m+2)/(2 pi) (phong), 0 otherwise
  double exponent = 0;    // Phong exponent m >= 0
  bool has_specular = false;
};

// Lambert and Phong only (the caller refuses the others); wo and n unit, dot(n, wo) > 0.
LineReceiver make_line_receiver(const Material& material, const Vec3& x, const Vec3& n,
                                const Vec3& wo);

// Integrals along one segment a -> b, prepared once for its many visible intervals.
class LineIntegrator {
 public:
  LineIntegrator(const LineReceiver& receiver, const Vec3& a, const Vec3& b,
                 const Vec3& light_normal);

  // integral_{t0}^{t1} max(0, n.wi) cos_l / r^2 |b - a| dt (geometry only; 0 <= t0 <= t1 <= 1).
  double diffuse(double t0, double t1) const;
  // integral_{t0}^{t1} max(0, R.wi)^m max(0, n.wi) cos_l / r^2 |b - a| dt.
  double specular(double t0, double t1) const;
  // Le * (diffuse BRDF * diffuse(t0,t1) + specular factor * specular(t0,t1)): the shading of
  // the visible interval, per unit perpendicular offset.
  Rgb radiance(const Rgb& emitted, double t0, double t1) const;

  bool zero() const { return zero_; }  // nothing can reach x from this line

 private:
  // theta of the point at parameter t (see the derivation above).
  double theta_at(double t) const;

  const LineReceiver* receiver_;
  bool zero_ = true;
  double prefactor_ = 0;                   // q / h^2
  double h_ = 0;                           // distance of x from the line
  double s_a_ = 0, s_b_ = 0;               // positions of a and b along e from the foot
  double normal_scale_ = 0, theta_n_ = 0;  // N, theta_n
  double mirror_scale_ = 0, theta_r_ = 0;  // M, theta_R
};

// The integral of cos^k over [u0, u1] within [-pi/2, pi/2], any real k >= 0 (exposed for tests).
double cosine_power_integral(double k, double u0, double u1);

}  // namespace penumbra
