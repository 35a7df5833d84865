// The closed-form line integrals (Billen & Dutré 2016 Appendices A and B, re-derived in
// core/lines/line_integrals.h) against adaptive Gauss-Legendre quadrature of the integrand in t,
// written here directly from vectors (no angles): relative error < 1e-6 over random
// configurations, short segments, segments nearly in the shading plane, shading points near the
// segment's line and Phong exponents 0..10^4.

#include "core/lines/line_integrals.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <random>
#include <vector>

namespace penumbra {
namespace {

constexpr double kNodes[4] = {0.1834346424956498, 0.5255324099163290, 0.7966664774136267,
                              0.9602898564975363};
constexpr double kWeights[4] = {0.3626837833783620, 0.3137066458778873, 0.2223810344533745,
                                0.1012285362903763};

double gauss8(const std::function<double(double)>& f, double lo, double hi) {
  double centre = 0.5 * (lo + hi), half = 0.5 * (hi - lo), sum = 0;
  for (int i = 0; i < 4; ++i)
    sum += kWeights[i] * (f(centre - half * kNodes[i]) + f(centre + half * kNodes[i]));
  return sum * half;
}

// Recursive bisection until the 8-point rule agrees with its two halves to `tolerance`
// (absolute, a fixed fraction of the whole integral).
double adaptive(const std::function<double(double)>& f, double lo, double hi, double whole,
                double tolerance, int depth) {
  double mid = 0.5 * (lo + hi);
  double left = gauss8(f, lo, mid), right = gauss8(f, mid, hi);
  if (depth <= 0 || std::abs(left + right - whole) <= tolerance) return left + right;
  return adaptive(f, lo, mid, left, tolerance, depth - 1) +
         adaptive(f, mid, hi, right, tolerance, depth - 1);
}

// integral of f over the panels (boundaries given, so narrow peaks are not missed), each panel
// refined until its error estimate is below relative_tolerance times the whole integral.
double integrate(const std::function<double(double)>& f, const std::vector<double>& panels,
                 double relative_tolerance) {
  double rough = 0;
  std::vector<double> pieces;
  for (size_t i = 0; i + 1 < panels.size(); ++i) {
    pieces.push_back(gauss8(f, panels[i], panels[i + 1]));
    rough += std::abs(pieces.back());
  }
  double tolerance = relative_tolerance * rough;
  double total = 0;
  for (size_t i = 0; i + 1 < panels.size(); ++i) {
    total += adaptive(f, panels[i], panels[i + 1], pieces[i], tolerance, 30);
  }
  return total;
}

struct Configuration {
  Vec3 x, n, wo, a, b, light_normal;
  double t0 = 0, t1 = 1;
};

// Reference integrals over t in [t0, t1], panels uniform in the angle subtended at x.
struct Reference {
  double diffuse = 0, specular = 0;
};
Reference reference(const Configuration& c, double exponent) {
  Vec3 mirror = 2.0 * dot(c.wo, c.n) * c.n - c.wo;
  double segment_length = length(c.b - c.a);
  auto geometry = [&](double t, double* cos_r) {
    Vec3 r = c.a + t * (c.b - c.a) - c.x;
    double r2 = dot(r, r);
    Vec3 wi = r / std::sqrt(r2);
    double cos_x = std::max(0.0, dot(c.n, wi));
    double cos_l = std::max(0.0, -dot(c.light_normal, wi));
    *cos_r = std::max(0.0, dot(mirror, wi));
    return cos_x * cos_l / r2 * segment_length;
  };
  std::function<double(double)> diffuse = [&](double t) {
    double cos_r;
    return geometry(t, &cos_r);
  };
  std::function<double(double)> specular = [&](double t) {
    double cos_r;
    double g = geometry(t, &cos_r);
    return cos_r > 0 ? g * std::pow(cos_r, exponent) : 0.0;
  };
  // Panel boundaries: 256 steps uniform in the angle at x between the two ends.
  Vec3 ra = c.a + c.t0 * (c.b - c.a) - c.x, rb = c.a + c.t1 * (c.b - c.a) - c.x;
  double angle = std::atan2(length(cross(ra, rb)), dot(ra, rb));
  std::vector<double> panels;
  constexpr int kPanels = 256;
  Vec3 e = normalize(c.b - c.a);
  double s0 = dot(ra, e), s1 = dot(rb, e);
  Vec3 foot = ra - s0 * e;
  double h = length(foot);
  double theta0 = std::atan2(s0, h);
  for (int i = 0; i <= kPanels; ++i) {
    double theta = theta0 + angle * i / kPanels;
    double s = h * std::tan(theta);
    double t = c.t0 + (c.t1 - c.t0) * (s - s0) / (s1 - s0);
    if (i == 0) t = c.t0;
    if (i == kPanels) t = c.t1;
    panels.push_back(std::clamp(t, c.t0, c.t1));
  }
  std::sort(panels.begin(), panels.end());
  return {integrate(diffuse, panels, 1e-13), integrate(specular, panels, 1e-13)};
}

Vec3 random_unit(std::mt19937_64& rng) {
  std::normal_distribution<double> normal;
  Vec3 v{normal(rng), normal(rng), normal(rng)};
  return normalize(v);
}

enum class Kind { Generic, Short, NearShadingPlane, NearLine };

// A random configuration of the given kind: light plane through the origin with normal
// light_normal, x in front of it.
Configuration random_configuration(std::mt19937_64& rng, Kind kind) {
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  Configuration c;
  c.light_normal = random_unit(rng);
  Vec3 tangent = normalize(cross(c.light_normal, random_unit(rng)));
  Vec3 bitangent = cross(c.light_normal, tangent);
  double scale = std::pow(10.0, 4.0 * uniform(rng) - 2.0);  // 1 cm .. 100 m
  double height = scale * (0.05 + 2.0 * uniform(rng));
  c.x = scale * ((uniform(rng) - 0.5) * 2.0 * tangent + (uniform(rng) - 0.5) * 2.0 * bitangent) +
        height * c.light_normal;
  double length_scale = scale * (0.1 + 2.0 * uniform(rng));
  if (kind == Kind::Short) length_scale *= std::pow(10.0, -2.0 - 5.0 * uniform(rng));
  Vec3 direction =
      std::cos(7.0 * uniform(rng)) * tangent + std::sin(7.0 * uniform(rng)) * bitangent;
  direction = normalize(direction);
  c.a = scale * (uniform(rng) - 0.5) * 2.0 * tangent + scale * (uniform(rng) - 0.5) * bitangent;
  c.b = c.a + length_scale * direction;
  // Shading normal: random, flipped towards the light half of the time so both clipped and
  // unclipped cases occur; wo random on n's side.
  c.n = random_unit(rng);
  if (uniform(rng) < 0.7 && dot(c.n, c.a - c.x) < 0) c.n = -c.n;
  if (kind == Kind::NearShadingPlane) {
    // n nearly perpendicular to both x->a and x->b: the segment nearly in the shading plane.
    Vec3 plane_normal = normalize(cross(c.a - c.x, c.b - c.x));
    double tilt = std::pow(10.0, -3.0 - 5.0 * uniform(rng)) * (uniform(rng) < 0.5 ? -1 : 1);
    c.n = normalize(plane_normal + tilt * normalize(c.a - c.x));
    if (uniform(rng) < 0.5) c.n = -c.n;
  }
  if (kind == Kind::NearLine) {
    // x close to the segment's line (off by a tiny fraction of its distance), still in front.
    double along = (uniform(rng) * 3.0 - 1.0);
    Vec3 on_line = c.a + along * (c.b - c.a);
    double offset = std::pow(10.0, -2.0 - 5.0 * uniform(rng)) * length(c.b - c.a);
    c.x = on_line + offset * normalize(c.light_normal + 0.3 * random_unit(rng));
    if (dot(c.x - c.a, c.light_normal) <= 0) c.x = on_line + offset * c.light_normal;
  }
  c.wo = random_unit(rng);
  if (dot(c.wo, c.n) < 0) c.wo = -c.wo;
  if (uniform(rng) < 0.3) {
    // Aim the mirror direction at the segment so the lobe is inside it.
    Vec3 target = normalize(c.a + uniform(rng) * (c.b - c.a) - c.x);
    if (dot(target, c.n) > 0) c.wo = 2.0 * dot(target, c.n) * c.n - target;
  }
  if (uniform(rng) < 0.3) {
    c.t0 = uniform(rng);
    c.t1 = c.t0 + (1.0 - c.t0) * uniform(rng);
  }
  return c;
}

// Values this small (lobes far from the segment, near double's underflow) carry no precision in
// either computation: they are compared absolutely.
constexpr double kUnderflow = 1e-290;

void expect_close(double got, double want, double relative, const std::string& what) {
  ASSERT_TRUE(std::isfinite(got)) << what;
  EXPECT_LE(std::abs(got - want), relative * std::abs(want) + kUnderflow)
      << what << " got " << got << " want " << want << " rel "
      << std::abs(got - want) / std::abs(want);
}

void check_kind(Kind kind, int count, uint64_t seed) {
  std::mt19937_64 rng(seed);
  const double exponents[] = {0, 1, 2, 3, 7.5, 20, 64, 65, 100, 333, 1000, 10000};
  double worst_diffuse = 0, worst_specular = 0;
  for (int i = 0; i < count; ++i) {
    Configuration c = random_configuration(rng, kind);
    double exponent = exponents[i % std::size(exponents)];
    Material phong;
    phong.type = MaterialType::Phong;
    phong.kd = {1, 1, 1};
    phong.ks = {1, 1, 1};
    phong.exponent = exponent;
    LineReceiver receiver = make_line_receiver(phong, c.x, c.n, c.wo);
    LineIntegrator integrator(receiver, c.a, c.b, c.light_normal);
    Reference want = reference(c, exponent);
    std::string what = "kind " + std::to_string(static_cast<int>(kind)) + " case " +
                       std::to_string(i) + " exponent " + std::to_string(exponent);
    double diffuse = integrator.diffuse(c.t0, c.t1), specular = integrator.specular(c.t0, c.t1);
    expect_close(diffuse, want.diffuse, 1e-6, what + " diffuse");
    expect_close(specular, want.specular, 1e-6, what + " specular");
    if (want.diffuse > kUnderflow) {
      worst_diffuse = std::max(worst_diffuse, std::abs(diffuse - want.diffuse) / want.diffuse);
    }
    if (want.specular > kUnderflow) {
      worst_specular = std::max(worst_specular, std::abs(specular - want.specular) / want.specular);
    }
  }
  std::printf("kind %d: largest relative error diffuse %.2e, specular %.2e\n",
              static_cast<int>(kind), worst_diffuse, worst_specular);
}

TEST(LineIntegrals, GenericConfigurations) {
  check_kind(Kind::Generic, 240, 1);
}
TEST(LineIntegrals, ShortSegments) {
  check_kind(Kind::Short, 120, 2);
}
TEST(LineIntegrals, SegmentsNearlyInTheShadingPlane) {
  check_kind(Kind::NearShadingPlane, 120, 3);
}
TEST(LineIntegrals, ShadingPointNearTheLine) {
  check_kind(Kind::NearLine, 120, 4);
}

TEST(LineIntegrals, CosinePowerIntegralAgainstQuadrature) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> uniform(-kPi / 2, kPi / 2);
  const double exponents[] = {0, 1, 2, 5, 63, 64, 66, 101, 1000.5, 4000, 10002};
  for (double k : exponents) {
    for (int i = 0; i < 40; ++i) {
      double u0 = uniform(rng), u1 = uniform(rng);
      if (u0 > u1) std::swap(u0, u1);
      if (i % 4 == 0) {  // around the peak
        u1 = std::abs(u1);
        u0 = -0.3 * u1;
      }
      std::function<double(double)> f = [k](double u) { return std::pow(std::cos(u), k); };
      std::vector<double> panels;
      for (int j = 0; j <= 256; ++j) panels.push_back(u0 + (u1 - u0) * j / 256);
      double want = integrate(f, panels, 1e-14);
      expect_close(
          cosine_power_integral(k, u0, u1), want, 1e-6,
          "k " + std::to_string(k) + " [" + std::to_string(u0) + ", " + std::to_string(u1) + "]");
    }
  }
}

TEST(LineIntegrals, LambertReceiverMatchesTheDiffuseIntegral) {
  Material lambert;
  lambert.albedo = {0.2, 0.5, 0.8};
  Configuration c;
  c.x = {0.1, 0.2, 0};
  c.n = {0, 0, 1};
  c.wo = normalize(Vec3{0.3, 0, 1});
  c.light_normal = {0, 0, -1};
  c.a = {-1, 0.5, 2};
  c.b = {1.5, 0.7, 2};
  LineReceiver receiver = make_line_receiver(lambert, c.x, c.n, c.wo);
  LineIntegrator integrator(receiver, c.a, c.b, c.light_normal);
  Reference want = reference(c, 1);
  Rgb got = integrator.radiance({2, 2, 2}, 0, 1);
  expect_close(got.x, 2 * 0.2 / kPi * want.diffuse, 1e-9, "red");
  expect_close(got.z, 2 * 0.8 / kPi * want.diffuse, 1e-9, "blue");
}

TEST(LineIntegrals, DegenerateInputIsZeroAndFinite) {
  Material phong;
  phong.type = MaterialType::Phong;
  phong.kd = {0.5, 0.5, 0.5};
  phong.ks = {0.5, 0.5, 0.5};
  phong.exponent = 10000;
  Vec3 n{0, 0, 1}, wo = normalize(Vec3{0.2, 0.1, 1});
  Vec3 light_normal{0, 0, -1};
  auto value = [&](const Vec3& x, const Vec3& a, const Vec3& b, double t0, double t1) {
    LineReceiver receiver = make_line_receiver(phong, x, n, wo);
    LineIntegrator integrator(receiver, a, b, light_normal);
    Rgb v = integrator.radiance({1, 1, 1}, t0, t1);
    EXPECT_TRUE(is_finite(v));
    return v.x;
  };
  // x on the light's plane, behind it, on the segment, zero-length segment, empty interval.
  EXPECT_EQ(value({0, 0, 1}, {-1, 0, 1}, {1, 0, 1}, 0, 1), 0.0);
  EXPECT_EQ(value({0, 0, 2}, {-1, 0, 1}, {1, 0, 1}, 0, 1), 0.0);
  EXPECT_EQ(value({0, 0, 1}, {-1, 0, 1}, {1, 0, 1}, 0.2, 0.7), 0.0);
  EXPECT_EQ(value({0, 0, 0}, {1, 0, 1}, {1, 0, 1}, 0, 1), 0.0);
  EXPECT_EQ(value({0, 0, 0}, {-1, 0, 1}, {1, 0, 1}, 0.5, 0.5), 0.0);
  // Segment entirely below the horizon of x (x in front of the light): nothing (never |cos|).
  {
    Vec3 flipped_light{0, 0, 1};  // light below x, facing up; x's normal faces up
    LineReceiver receiver = make_line_receiver(phong, {0, 0, 2}, n, wo);
    LineIntegrator integrator(receiver, {-1, 0, 1}, {1, 0, 1}, flipped_light);
    EXPECT_EQ(integrator.diffuse(0, 1), 0.0);
    EXPECT_EQ(integrator.specular(0, 1), 0.0);
  }
  // Non-finite input.
  double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(value({0, 0, 0}, {-inf, 0, 1}, {1, 0, 1}, 0, 1), 0.0);
  // 1 cm segment at 40 m and a 1 mm segment at 1 mm: finite and positive.
  EXPECT_GT(value({0, 0, 0}, {0, 0, 40}, {0.01, 0, 40}, 0, 1), 0.0);
  EXPECT_GT(value({0, 0, 0}, {-0.0005, 0, 0.001}, {0.0005, 0, 0.001}, 0, 1), 0.0);
}

}  // namespace
}  // namespace penumbra
