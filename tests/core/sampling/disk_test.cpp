// Shirley-Chiu concentric map: lands in the unit disk, preserves area, continuous.

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/sampling/counter_random.h"
#include "core/sampling/pattern.h"
#include "sample_statistics.h"

namespace penumbra {
namespace {

double norm(const Vec2& p) {
  return std::sqrt(p.x * p.x + p.y * p.y);
}

TEST(ConcentricDisk, LandsInTheDiskAndKeepsTheBoundary) {
  constexpr int kGrid = 400;
  for (int i = 0; i <= kGrid; ++i) {
    for (int j = 0; j <= kGrid; ++j) {
      Vec2 u(static_cast<double>(i) / kGrid, static_cast<double>(j) / kGrid);
      Vec2 p = square_to_disk_concentric(u);
      ASSERT_TRUE(std::isfinite(p.x) && std::isfinite(p.y));
      ASSERT_LE(norm(p), 1.0 + 1e-15);
      // Concentric squares map to concentric circles: radius = Chebyshev distance from centre.
      double square_radius = std::max(std::abs(2 * u.x - 1), std::abs(2 * u.y - 1));
      ASSERT_NEAR(norm(p), square_radius, 1e-15);
    }
  }
  Vec2 centre = square_to_disk_concentric({0.5, 0.5});
  EXPECT_EQ(centre.x, 0.0);
  EXPECT_EQ(centre.y, 0.0);
  Vec2 right = square_to_disk_concentric({1.0, 0.5});
  EXPECT_NEAR(right.x, 1.0, 1e-15);
  EXPECT_NEAR(right.y, 0.0, 1e-15);
  Vec2 corner = square_to_disk_concentric({1.0, 1.0});  // the diagonal goes to 45 degrees
  EXPECT_NEAR(corner.x, std::sqrt(0.5), 1e-15);
  EXPECT_NEAR(corner.y, std::sqrt(0.5), 1e-15);
}

TEST(ConcentricDisk, PreservesArea) {
  // Uniform points of the square must be uniform in the disk: chi-square over 8 rings of equal
  // area (r^2 bins) times 16 angular sectors.
  constexpr int kRings = 8, kSectors = 16;
  constexpr uint32_t kPoints = 1u << 19;
  std::vector<uint64_t> bins(kRings * kSectors, 0);
  StreamRandom rng({21, 0, 0, 0});
  for (uint32_t i = 0; i < kPoints; ++i) {
    Vec2 p = square_to_disk_concentric({rng.uniform(i, 0), rng.uniform(i, 1)});
    double r2 = p.x * p.x + p.y * p.y;
    double angle = std::atan2(p.y, p.x) + kPi;  // [0, 2 pi]
    int ring = std::min(kRings - 1, static_cast<int>(r2 * kRings));
    int sector = std::min(kSectors - 1, static_cast<int>(angle / (2 * kPi) * kSectors));
    ++bins[ring * kSectors + sector];
  }
  EXPECT_LT(testing::chi_square_equal(bins),
            testing::chi_square_critical_0001(kRings * kSectors - 1));
}

TEST(ConcentricDisk, PreservesAreaOfSmallSquares) {
  // The map has a constant Jacobian: the unit square (area 1) goes to the unit disk (area pi), so
  // every small square of side h maps to a region of area pi h^2. Measured by the shoelace area
  // of its mapped corners, anywhere except across the diagonals (where the map has a kink).
  const double h = 1e-4;
  StreamRandom rng({22, 0, 0, 0});
  for (uint32_t i = 0; i < 2000; ++i) {
    Vec2 u(rng.uniform(i, 0) * (1 - h), rng.uniform(i, 1) * (1 - h));
    // Skip squares that straddle a diagonal.
    double a0 = 2 * u.x - 1, b0 = 2 * u.y - 1, a1 = a0 + 2 * h, b1 = b0 + 2 * h;
    bool same_wedge = true;
    for (double a : {a0, a1}) {
      for (double b : {b0, b1})
        same_wedge &= (std::abs(a) > std::abs(b)) == (std::abs(a0) > std::abs(b0));
    }
    if (!same_wedge || a0 * a1 <= 0 || b0 * b1 <= 0) continue;
    Vec2 corners[4] = {square_to_disk_concentric(u), square_to_disk_concentric({u.x + h, u.y}),
                       square_to_disk_concentric({u.x + h, u.y + h}),
                       square_to_disk_concentric({u.x, u.y + h})};
    double area = 0;
    for (int k = 0; k < 4; ++k) {
      const Vec2& p = corners[k];
      const Vec2& q = corners[(k + 1) % 4];
      area += p.x * q.y - q.x * p.y;
    }
    area = std::abs(area) / 2;
    EXPECT_NEAR(area / (h * h), kPi, 1e-3 * kPi);
  }
}

TEST(ConcentricDisk, IsContinuous) {
  // Lipschitz: the map's derivative is bounded (|d/du| <= 2 sqrt(1 + (pi/2)^2) < 4), so steps of
  // delta move the image by at most 4 delta, including across the diagonals and the centre.
  const double delta = 1e-7;
  StreamRandom rng({23, 0, 0, 0});
  auto check = [&](const Vec2& u, const Vec2& v) {
    Vec2 p = square_to_disk_concentric(u), q = square_to_disk_concentric(v);
    double step = std::hypot(u.x - v.x, u.y - v.y);
    ASSERT_LE(std::hypot(p.x - q.x, p.y - q.y), 4.0 * step + 1e-15)
        << "(" << u.x << ", " << u.y << ")";
  };
  for (uint32_t i = 0; i < 100000; ++i) {
    Vec2 u(rng.uniform(i, 0), rng.uniform(i, 1));
    check(u, {u.x + delta, u.y});
    check(u, {u.x, u.y + delta});
  }
  // Points on and around the diagonals and through the centre.
  for (int i = 0; i <= 1000; ++i) {
    double t = i / 1000.0;
    check({t, t}, {t + delta, t});
    check({t, t}, {t, t + delta});
    check({t, 1 - t}, {t + delta, 1 - t});
    check({t, 1 - t}, {t, 1 - t - delta});
    check({0.5, t}, {0.5 + delta, t});
    check({t, 0.5}, {t, 0.5 - delta});
  }
  // The smallest steps away from the centre, where both wedge formulas divide by tiny numbers.
  double next_up = std::nextafter(0.5, 1.0), next_down = std::nextafter(0.5, 0.0);
  check({0.5, 0.5}, {next_up, 0.5});
  check({0.5, 0.5}, {next_down, next_up});
  check({next_up, 0.5}, {0.5, next_down});
}

}  // namespace
}  // namespace penumbra
