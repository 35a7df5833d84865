// The strata grid rule and the stratum arithmetic shared by the grid patterns.

#include "core/sampling/strata.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/sampling/counter_random.h"

namespace penumbra {
namespace {

TEST(StrataGrid, SquareCountsGiveSquareGrids) {
  for (uint32_t side = 1; side <= 32; ++side) {
    StrataGrid grid = strata_grid(side * side, 1.0);
    EXPECT_EQ(grid.columns, side);
    EXPECT_EQ(grid.rows, side);
    EXPECT_EQ(grid.leftover, 0u);
  }
}

TEST(StrataGrid, ThinLightsGetOneRowAlongTheirLength) {
  for (uint32_t n : {1u, 2u, 7u, 16u, 64u}) {
    StrataGrid wide = strata_grid(n, static_cast<double>(n));  // aspect >= N
    EXPECT_EQ(wide.columns, n);
    EXPECT_EQ(wide.rows, 1u);
    EXPECT_EQ(wide.leftover, 0u);
    StrataGrid tall = strata_grid(n, 1.0 / (4.0 * n));  // taller than wide: swapped
    EXPECT_EQ(tall.columns, 1u);
    EXPECT_EQ(tall.rows, n);
    EXPECT_EQ(tall.leftover, 0u);
    StrataGrid line = strata_grid(n, std::numeric_limits<double>::infinity());
    EXPECT_EQ(line.columns, n);
    EXPECT_EQ(line.rows, 1u);
  }
}

TEST(StrataGrid, FollowsTheRoundedSquareRootRule) {
  for (uint32_t n = 1; n <= 200; ++n) {
    for (double aspect : {1.0, 1.5, 2.0, 3.7, 10.0, 0.5, 0.1, 0.27}) {
      StrataGrid grid = strata_grid(n, aspect);
      double elongation = aspect >= 1.0 ? aspect : 1.0 / aspect;
      uint32_t long_side = aspect >= 1.0 ? grid.columns : grid.rows;
      uint32_t short_side = aspect >= 1.0 ? grid.rows : grid.columns;
      uint32_t expected_long = elongation >= n
                                   ? n
                                   : static_cast<uint32_t>(std::clamp(
                                         std::round(std::sqrt(n * elongation)), 1.0, double(n)));
      EXPECT_EQ(long_side, expected_long) << n << " " << aspect;
      EXPECT_EQ(short_side, n / expected_long);
      EXPECT_EQ(grid.cells() + grid.leftover, n);
      EXPECT_LT(grid.leftover, long_side);
      EXPECT_EQ(grid.leftover_along_x, aspect >= 1.0);
    }
  }
}

TEST(StrataGrid, MeaninglessAspectsCountAsSquare) {
  for (double aspect : {0.0, -2.0, std::numeric_limits<double>::quiet_NaN()}) {
    StrataGrid grid = strata_grid(16, aspect);
    EXPECT_EQ(grid.columns, 4u);
    EXPECT_EQ(grid.rows, 4u);
  }
  StrataGrid empty = strata_grid(0, 1.0);
  EXPECT_EQ(empty.cells() + empty.leftover, 0u);
}

TEST(PointInStratum, StaysInItsStratumEvenAtTheEdges) {
  // u at and next to 0 and 1 (where (index + u) / count rounds across a boundary), for many
  // stratum counts including non-powers of two.
  const double edges[] = {0.0,
                          std::numeric_limits<double>::denorm_min(),
                          1e-17,
                          0.5,
                          1.0 - 1e-16,
                          kOneMinusEpsilon,
                          std::nextafter(kOneMinusEpsilon, 0.0)};
  for (uint64_t count : {1ull, 2ull, 3ull, 7ull, 10ull, 49ull, 729ull, 59049ull, 1000003ull}) {
    for (uint64_t index : {uint64_t{0}, count / 3, count / 2, count - 1}) {
      for (double u : edges) {
        double v = point_in_stratum(index, count, u);
        EXPECT_GE(v, 0.0);
        EXPECT_LT(v, 1.0);
        EXPECT_EQ(stratum_of(v, count), index) << count << " " << index << " " << u;
        EXPECT_EQ(std::floor(v * static_cast<double>(count)), static_cast<double>(index));
        EXPECT_NEAR(v, (index + u) / count, 4e-16);
      }
    }
  }
}

TEST(PointInStratum, RandomPositionsStayInTheirStrata) {
  StreamRandom rng({1, 2, 3, 4});
  for (uint32_t i = 0; i < 200000; ++i) {
    uint64_t count = 1 + (rng.bits(i, 0) >> 44);
    uint64_t index = (rng.bits(i, 1) >> 11) % count;
    double v = point_in_stratum(index, count, rng.uniform(i, 2));
    ASSERT_EQ(stratum_of(v, count), index);
    ASSERT_LT(v, 1.0);
  }
}

}  // namespace
}  // namespace penumbra
