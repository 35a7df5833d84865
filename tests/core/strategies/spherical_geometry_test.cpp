// core/math/spherical_triangle.h, core/math/solid_angle_polygon.h and
// core/math/spherical_rectangle.h: solid angles against
// closed forms, the defining properties of the parametrizations, inverses and round trips.

#include <gtest/gtest.h>

#include "core/math/solid_angle_polygon.h"
#include "core/math/spherical_rectangle.h"
#include "core/math/spherical_triangle.h"
#include "tests/core/strategies/test_support.h"

namespace penumbra {
namespace {

using test::relative_difference;
using test::Rng;

// Solid angle of an a x b rectangle seen from distance d on its central axis.
double centered_rectangle_solid_angle(double a, double b, double d) {
  return 4.0 * std::asin(a * b / std::sqrt((a * a + 4 * d * d) * (b * b + 4 * d * d)));
}

TEST(TriangleSolidAngle, ClosedForms) {
  EXPECT_NEAR(triangle_solid_angle({1, 0, 0}, {0, 1, 0}, {0, 0, 1}), kPi / 2, 1e-15);
  EXPECT_NEAR(triangle_solid_angle({3, 0, 0}, {0, 0.5, 0}, {0, 0, 7}), kPi / 2, 1e-15);
  for (double d : {0.01, 1.0, 40.0}) {
    double a = 0.7, b = 0.3;
    Vec3 c00{-a / 2, -b / 2, d}, c10{a / 2, -b / 2, d}, c11{a / 2, b / 2, d}, c01{-a / 2, b / 2, d};
    double sum = triangle_solid_angle(c00, c10, c11) + triangle_solid_angle(c00, c11, c01);
    EXPECT_LE(relative_difference(sum, centered_rectangle_solid_angle(a, b, d)), 1e-13) << d;
  }
  // 1 cm triangle 40 m away, face on: area / r^2 to first order (relative 1e-8 here).
  double omega = triangle_solid_angle({0, 0, 40}, {0.01, 0, 40}, {0, 0.01, 40});
  EXPECT_LE(relative_difference(omega, 0.5e-4 / 1600), 1e-7);
}

// Peters' construction (core/math/solid_angle_polygon.h, the `sa` of polygons and of the
// SolidAngleStrategy's fans) on triangles of every size.
TEST(SphericalTriangle, SubtriangleHasTheRequestedSolidAngleAndSamplesStayInside) {
  Rng rng(3);
  for (int trial = 0; trial < 300; ++trial) {
    Vec3 a = rng.unit_vector(), b = rng.unit_vector(), c = rng.unit_vector();
    if (trial % 3 == 0) {  // small triangles
      b = normalize(a + 0.01 * b);
      c = normalize(a + 0.01 * c);
    }
    PreparedSphericalTriangle t = prepare_spherical_triangle(a, b, c);
    double area = t.solid_angle;
    ASSERT_GT(area, 0);
    EXPECT_LE(relative_difference(area, triangle_solid_angle(a, b, c)), 1e-9);
    for (double xi0 : {0.0, 0.1, 0.5, 0.9, 1.0}) {
      // xi1 = 1 gives the constructed vertex v2'; (v0, v1, v2') has solid angle xi0 * A.
      Vec3 v2_prime = sample_spherical_triangle(t, {xi0, 1.0});
      EXPECT_NEAR(triangle_solid_angle(t.v0, t.v1, v2_prime), xi0 * area, 1e-9 * area);
      EXPECT_LE(length(sample_spherical_triangle(t, {xi0, 0.0}) - t.v1), 1e-12);
    }
    // Inside: on the inner side of the three great circles.
    double orientation = dot(a, cross(b, c)) > 0 ? 1.0 : -1.0;
    for (int i = 0; i < 20; ++i) {
      Vec3 w = sample_spherical_triangle(t, rng.uniform2());
      ASSERT_NEAR(length(w), 1.0, 1e-12);
      double tolerance = 1e-12;
      EXPECT_GE(orientation * dot(w, cross(a, b)), -tolerance);
      EXPECT_GE(orientation * dot(w, cross(b, c)), -tolerance);
      EXPECT_GE(orientation * dot(w, cross(c, a)), -tolerance);
    }
  }
}

TEST(SphericalRectangle, SolidAngleMatchesClosedFormAndTriangles) {
  for (double d : {1e-4, 0.3, 1.0, 40.0}) {
    auto r = SphericalRectangle::prepare({0, 0, 0}, {-0.35, -0.15, d}, {0.7, 0, 0}, {0, 0.3, 0});
    ASSERT_TRUE(r.has_value());
    EXPECT_LE(relative_difference(r->solid_angle, centered_rectangle_solid_angle(0.7, 0.3, d)),
              1e-12)
        << d;
  }
  Rng rng(5);
  for (int trial = 0; trial < 200; ++trial) {
    Vec3 o = 2.0 * rng.unit_vector();
    Frame f = Frame::from_normal(rng.unit_vector());
    Vec3 corner = 0.5 * rng.unit_vector();
    Vec3 ex = (0.1 + rng.uniform()) * f.s, ey = (0.1 + rng.uniform()) * f.t;
    auto r = SphericalRectangle::prepare(o, corner, ex, ey);
    ASSERT_TRUE(r.has_value());
    double two_triangles = triangle_solid_angle(corner - o, corner + ex - o, corner + ex + ey - o) +
                           triangle_solid_angle(corner - o, corner + ex + ey - o, corner + ey - o);
    EXPECT_LE(relative_difference(r->solid_angle, two_triangles), 1e-10);
  }
  // The point in the rectangle's plane: no parametrization.
  EXPECT_FALSE(SphericalRectangle::prepare({0.1, 0.1, 0}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}));
}

TEST(SphericalRectangle, ParametrizationPropertiesAndInverse) {
  Rng rng(7);
  for (int trial = 0; trial < 200; ++trial) {
    Vec3 o = 2.0 * rng.unit_vector();
    Frame f = Frame::from_normal(rng.unit_vector());
    Vec3 corner = 0.5 * rng.unit_vector();
    Vec3 ex = (0.1 + rng.uniform()) * f.s, ey = (0.1 + rng.uniform()) * f.t;
    auto r = SphericalRectangle::prepare(o, corner, ex, ey);
    ASSERT_TRUE(r.has_value());
    EXPECT_NEAR(r->line_x(0.0), r->x0, 1e-9 * (r->x1 - r->x0));
    EXPECT_NEAR(r->line_x(1.0), r->x1, 1e-9 * (r->x1 - r->x0));
    double previous = r->x0;
    for (int i = 0; i <= 20; ++i) {
      double u = i / 20.0;
      double xu = r->line_x(u);
      EXPECT_GE(xu, previous - 1e-12);
      previous = xu;
      // Step 1's defining property: the sub-rectangle up to the line has solid angle u S.
      EXPECT_NEAR(r->solid_angle_up_to(xu), u * r->solid_angle, 1e-9 * r->solid_angle);
    }
    for (int i = 0; i < 20; ++i) {
      Vec2 uv = rng.uniform2();
      Vec3 p = r->sample(uv);
      // On the rectangle.
      Vec3 d = p - corner;
      EXPECT_NEAR(dot(d, normalize(cross(ex, ey))), 0.0, 1e-12);
      EXPECT_GE(dot(d, ex) / dot(ex, ex), -1e-12);
      EXPECT_LE(dot(d, ex) / dot(ex, ex), 1 + 1e-12);
      EXPECT_GE(dot(d, ey) / dot(ey, ey), -1e-12);
      EXPECT_LE(dot(d, ey) / dot(ey, ey), 1 + 1e-12);
      // Round trip through the inverse.
      Vec2 back = r->invert(p);
      EXPECT_NEAR(back.x, uv.x, 1e-8);
      EXPECT_NEAR(back.y, uv.y, 1e-8);
      // h <-> y on the line through the point.
      Vec2 xy = r->local_xy(p);
      auto bounds = r->h_bounds(xy.x);
      double h = SphericalRectangle::h_of_y(bounds.d, xy.y);
      EXPECT_GE(h, bounds.h0 - 1e-12);
      EXPECT_LE(h, bounds.h1 + 1e-12);
      EXPECT_NEAR(r->y_of_h(bounds.d, h), xy.y, 1e-9);
      EXPECT_LE(length(r->point_at(xy.x, xy.y) - p), 1e-12);
    }
  }
}

TEST(SphericalRectangle, LineSamplingDensityIntegratesToOneOverVisibleParts) {
  // Salesin & Jarosz Eq. 16-19 with one occluded interval per line: line x = line_x(u) with u
  // uniform, h uniform in the visible h-intervals. Integrating the density (converted to area
  // measure) over the visible part of the rectangle, line by line, must give 1 for every
  // occlusion pattern that leaves every line some visible part.
  auto r = SphericalRectangle::prepare({0.2, -0.1, 0}, {-0.4, -0.3, 0.8}, {0.9, 0, 0}, {0, 0.7, 0});
  ASSERT_TRUE(r.has_value());
  EXPECT_NEAR(r->line_sample_solid_angle_pdf(0.3, 0.3), 1.0 / r->solid_angle, 1e-15);
  EXPECT_EQ(r->line_sample_solid_angle_pdf(0.3, 0.0), 0.0);
  // Occluder: the band t in [0.3, 0.55] of every line, shifted with x.
  auto occluded = [&](double x_fraction, double t) {
    double shift = 0.2 * x_fraction;
    return t > 0.3 + shift && t < 0.55 + shift;
  };
  int nx = 400, ny = 400;
  double total = 0;
  double dx = (r->x1 - r->x0) / nx, dy = (r->y1 - r->y0) / ny;
  for (int i = 0; i < nx; ++i) {
    double x = r->x0 + (i + 0.5) * dx;
    double x_fraction = (i + 0.5) / nx;
    auto bounds = r->h_bounds(x);
    // Visible h-length: the whole line minus the occluded band's h-interval.
    double ya = r->y_at_fraction(0.3 + 0.2 * x_fraction),
           yb = r->y_at_fraction(0.55 + 0.2 * x_fraction);
    double visible = (bounds.h1 - bounds.h0) - (SphericalRectangle::h_of_y(bounds.d, yb) -
                                                SphericalRectangle::h_of_y(bounds.d, ya));
    for (int j = 0; j < ny; ++j) {
      double t = (j + 0.5) / ny;
      if (occluded(x_fraction, t)) continue;
      double y = r->y_at_fraction(t);
      Vec3 d{x, y, r->z0};
      double r2 = length_squared(d);
      double area_pdf = r->line_sample_solid_angle_pdf(bounds.h1 - bounds.h0, visible) * (-r->z0) /
                        (r2 * std::sqrt(r2));
      total += area_pdf * dx * dy;
    }
  }
  EXPECT_NEAR(total, 1.0, 2e-3);
}

TEST(SphericalRectangle, TinyDistantRectangleStaysAccurateAndFinite) {
  // The parametrization keeps its defining property (sub-rectangle solid angle u S) for a 1 cm
  // and a 1 mm light 40 m away, head on and seen obliquely from 25 m aside.
  for (double size : {0.01, 0.001}) {
    for (double aside : {0.3, 25.0}) {
      auto tiny = SphericalRectangle::prepare({aside, 0.2, 0}, {-size / 2, -size / 2, 40},
                                              {size, 0, 0}, {0, size, 0});
      ASSERT_TRUE(tiny.has_value());
      for (int i = 0; i <= 100; ++i) {
        double u = i / 100.0;
        EXPECT_NEAR(tiny->solid_angle_up_to(tiny->line_x(u)) / tiny->solid_angle, u, 1e-7)
            << size << " " << aside;
      }
    }
  }

  auto r =
      SphericalRectangle::prepare({0.3, 0.2, 0}, {-0.005, -0.005, 40}, {0.01, 0, 0}, {0, 0.01, 0});
  ASSERT_TRUE(r.has_value());
  double approx = 1e-4 * 40 / std::pow(length(Vec3{-0.3, -0.2, 40}), 3);
  EXPECT_LE(relative_difference(r->solid_angle, approx), 1e-4);
  Rng rng(9);
  for (int i = 0; i < 1000; ++i) {
    Vec2 uv = i < 4 ? Vec2{double(i & 1), double(i >> 1)} : rng.uniform2();
    Vec3 p = r->sample(uv);
    ASSERT_TRUE(is_finite(p));
    EXPECT_NEAR(p.z, 40.0, 1e-12);
    EXPECT_GE(p.x, -0.005 - 1e-12);
    EXPECT_LE(p.x, 0.005 + 1e-12);
  }
}

}  // namespace
}  // namespace penumbra
