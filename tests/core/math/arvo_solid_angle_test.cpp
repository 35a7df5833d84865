// Arvo's original spherical triangle sampling (core/math/arvo_solid_angle.h, the `sa-arvo`
// variant of polygon_bench): the same map as Peters' construction (Peters 2021 Sec. 5), so for
// well-conditioned triangles both give the same direction for the same (u.x, u.y); its Girard
// area agrees with van Oosterom & Strackee's there; samples lie in the polygon; for tiny distant
// triangles (Peters Fig. 7) its area loses most digits but it stays finite.

#include "core/math/arvo_solid_angle.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <random>

#include "core/math/solid_angle_polygon.h"
#include "tests/support/polygon_test_util.h"

namespace penumbra {
namespace {

using polygon_test::hits_polygon;
using polygon_test::random_unit_vector;
using polygon_test::uniform;

TEST(ArvoSolidAngle, SameMapAsPetersConstruction) {
  std::mt19937_64 rng(37);
  int compared = 0;
  for (int k = 0; k < 4000; ++k) {
    Vec3 a = random_unit_vector(rng), b = random_unit_vector(rng), c = random_unit_vector(rng);
    // Peters' preparation orders the vertices so that det(a, b, c) >= 0; give both that order.
    if (dot(a, cross(b, c)) < 0) std::swap(b, c);
    PreparedSphericalTriangle peters = prepare_spherical_triangle(a, b, c);
    ArvoSphericalTriangle arvo = prepare_arvo_triangle(a, b, c);
    if (peters.solid_angle < 1e-3 || peters.solid_angle > 2 * kPi - 1e-3) continue;
    ++compared;
    EXPECT_NEAR(arvo.area, peters.solid_angle, 1e-9 * peters.solid_angle) << k;
    for (int s = 0; s < 4; ++s) {
      Vec2 u{uniform(rng), uniform(rng)};
      Vec3 d_arvo = sample_arvo_triangle(arvo, u);
      Vec3 d_peters = sample_spherical_triangle(peters, u);
      EXPECT_LT(length(d_arvo - d_peters), 1e-7) << k << " u " << u.x << " " << u.y;
    }
  }
  EXPECT_GT(compared, 1000);
}

TEST(ArvoSolidAngle, PolygonSamplesLieInThePolygonAndAgreeOnTheSolidAngle) {
  std::mt19937_64 rng(41);
  for (int trial = 0; trial < 1000; ++trial) {
    int n = 3 + int(uniform(rng) * 6);
    Vec3 center = random_unit_vector(rng) * (0.5 + 2 * uniform(rng));
    std::vector<Vec3> polygon = polygon_test::random_convex_polygon(
        rng, n, center, random_unit_vector(rng), length(center) * (0.1 + uniform(rng)));
    ArvoPolygonSampler arvo(polygon);
    SolidAnglePolygonSampler peters(polygon);
    if (peters.solid_angle() < 1e-3) continue;
    EXPECT_NEAR(arvo.solid_angle(), peters.solid_angle(), 1e-8 * peters.solid_angle());
    for (int k = 0; k < 8; ++k) {
      std::optional<Vec3> d = arvo.sample({uniform(rng), uniform(rng)});
      ASSERT_TRUE(d.has_value());
      EXPECT_NEAR(length(*d), 1.0, 1e-12);
      EXPECT_TRUE(hits_polygon(polygon, *d, 1e-6)) << "trial " << trial;
    }
  }
}

// Peters Fig. 7: Girard's formula cancels alpha + beta + gamma ~ pi down to 6e-8 (1 cm at 40 m)
// and 6e-10 (1 mm): Arvo's area loses digits (measured: relative errors 1.3e-8 and 7.9e-7
// against Peters', printed), Peters' keeps ~12. Samples stay finite (or absent), never NaN.
TEST(ArvoSolidAngle, TinyDistantLightsStayFinite) {
  for (double side : {0.01, 0.001}) {
    std::vector<Vec3> square = {{-side / 2, -side / 2, 40},
                                {side / 2, -side / 2, 40},
                                {side / 2, side / 2, 40},
                                {-side / 2, side / 2, 40}};
    ArvoPolygonSampler arvo(square);
    double exact = SolidAnglePolygonSampler(square).solid_angle();
    std::printf("side %g m at 40 m: solid angle Peters %.12g, Arvo %.12g (relative error %.2g)\n",
                side, exact, arvo.solid_angle(), std::abs(arvo.solid_angle() - exact) / exact);
    EXPECT_TRUE(std::isfinite(arvo.solid_angle()));
    std::mt19937_64 rng(43);
    for (int k = 0; k < 10000; ++k) {
      std::optional<Vec3> d = arvo.sample({uniform(rng), uniform(rng)});
      if (d) {
        EXPECT_TRUE(is_finite(*d));
      }
    }
  }
}

}  // namespace
}  // namespace penumbra
