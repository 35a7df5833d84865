// Every sample pattern: range, stratification promises, pooled uniformity, decorrelation across
// pixels, determinism; plus the names of SCENE_FORMAT.md.

#include "core/sampling/pattern.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "core/sampling/counter_random.h"
#include "core/sampling/strata.h"
#include "sample_statistics.h"

namespace penumbra {
namespace {

constexpr Pattern kAllPatterns[] = {
    Pattern::Random, Pattern::Stratified, Pattern::Uniform, Pattern::UniformJitter,
    Pattern::Halton, Pattern::Sobol,      Pattern::Cmj};
// Patterns with a strata grid in 2D (strata.h) and N equal strata in 1D.
constexpr Pattern kGridPatterns[] = {Pattern::Stratified, Pattern::Uniform, Pattern::UniformJitter,
                                     Pattern::Cmj};
// Patterns whose points are random (all but uniform).
constexpr Pattern kRandomizedPatterns[] = {Pattern::Random,        Pattern::Stratified,
                                           Pattern::UniformJitter, Pattern::Halton,
                                           Pattern::Sobol,         Pattern::Cmj};

std::string name_of(Pattern p) {
  return std::string(pattern_name(p));
}

std::vector<Vec2> points_2d(Pattern pattern, const StreamKey& key, uint32_t n, double aspect) {
  std::vector<Vec2> points(n);
  generate_2d(pattern, key, aspect, points);
  return points;
}

std::vector<double> points_1d(Pattern pattern, const StreamKey& key, uint32_t n) {
  std::vector<double> points(n);
  generate_1d(pattern, key, points);
  return points;
}

TEST(PatternNames, RoundTripTheSceneFormatNames) {
  const char* names[] = {"random", "stratified", "uniform", "uniform-jitter",
                         "halton", "sobol",      "cmj"};
  for (size_t i = 0; i < std::size(kAllPatterns); ++i) {
    EXPECT_EQ(pattern_name(kAllPatterns[i]), names[i]);
    ASSERT_TRUE(parse_pattern(names[i]).has_value());
    EXPECT_EQ(*parse_pattern(names[i]), kAllPatterns[i]);
  }
  EXPECT_FALSE(parse_pattern("").has_value());
  EXPECT_FALSE(parse_pattern("Stratified").has_value());
  EXPECT_FALSE(parse_pattern("uniform_jitter").has_value());
  EXPECT_FALSE(parse_pattern("cmj ").has_value());
}

TEST(Patterns, ValuesInUnitIntervalAndDeterministic) {
  for (Pattern pattern : kAllPatterns) {
    for (uint32_t n : {0u, 1u, 2u, 3u, 5u, 16u, 17u, 64u, 100u, 257u}) {
      for (double aspect : {1.0, 3.0, 0.2, 1e6}) {
        for (uint64_t pixel = 0; pixel < 20; ++pixel) {
          StreamKey key{17, pixel, 2, 1};
          std::vector<Vec2> points = points_2d(pattern, key, n, aspect);
          ASSERT_EQ(points.size(), n);
          for (const Vec2& p : points) {
            ASSERT_TRUE(p.x >= 0.0 && p.x < 1.0 && p.y >= 0.0 && p.y < 1.0)
                << name_of(pattern) << " n=" << n << " (" << p.x << ", " << p.y << ")";
          }
          std::vector<Vec2> again = points_2d(pattern, key, n, aspect);
          for (uint32_t i = 0; i < n; ++i) {
            ASSERT_EQ(points[i].x, again[i].x);
            ASSERT_EQ(points[i].y, again[i].y);
          }
        }
      }
      for (uint64_t pixel = 0; pixel < 20; ++pixel) {
        std::vector<double> line = points_1d(pattern, {17, pixel, 2, 1}, n);
        for (double v : line) ASSERT_TRUE(v >= 0.0 && v < 1.0) << name_of(pattern);
        EXPECT_EQ(line, points_1d(pattern, {17, pixel, 2, 1}, n));
      }
    }
  }
}

TEST(Patterns, DifferentStreamsDiffer) {
  for (Pattern pattern : kRandomizedPatterns) {
    StreamKey key{5, 100, 0, 0};
    std::vector<Vec2> base = points_2d(pattern, key, 8, 1.0);
    for (int field = 0; field < 4; ++field) {
      StreamKey other = key;
      if (field == 0) other.seed += 1;
      if (field == 1) other.pixel += 1;
      if (field == 2) other.pass += 1;
      if (field == 3) other.stream += 1;
      std::vector<Vec2> changed = points_2d(pattern, other, 8, 1.0);
      int equal = 0;
      for (int i = 0; i < 8; ++i) equal += base[i].x == changed[i].x || base[i].y == changed[i].y;
      EXPECT_EQ(equal, 0) << name_of(pattern) << " field " << field;
    }
  }
}

// Stratification: exactly one sample per grid cell for the first cells() samples, exactly one
// per leftover band for the rest (strata.h). Counts include square, prime, thin (N x 1) and tall.
void expect_grid_stratification(Pattern pattern, uint32_t n, double aspect, const StreamKey& key) {
  StrataGrid grid = strata_grid(n, aspect);
  std::vector<Vec2> points = points_2d(pattern, key, n, aspect);
  std::vector<int> cell_count(grid.cells(), 0);
  for (uint32_t i = 0; i < grid.cells(); ++i) {
    uint64_t column = stratum_of(points[i].x, grid.columns);
    uint64_t row = stratum_of(points[i].y, grid.rows);
    ++cell_count[row * grid.columns + column];
  }
  for (int c : cell_count) {
    ASSERT_EQ(c, 1) << name_of(pattern) << " n=" << n << " aspect=" << aspect << " grid "
                    << grid.columns << "x" << grid.rows;
  }
  std::vector<int> band_count(grid.leftover, 0);
  for (uint32_t band = 0; band < grid.leftover; ++band) {
    const Vec2& p = points[grid.cells() + band];
    ++band_count[stratum_of(grid.leftover_along_x ? p.x : p.y, grid.leftover)];
  }
  for (int c : band_count) ASSERT_EQ(c, 1) << name_of(pattern) << " n=" << n;
}

TEST(Patterns, GridPatternsPutOneSamplePerStratum) {
  for (Pattern pattern : kGridPatterns) {
    for (uint32_t n : {1u, 2u, 3u, 4u, 5u, 7u, 9u, 12u, 13u, 16u, 31u, 36u, 64u, 97u, 256u}) {
      for (double aspect : {1.0, 2.0, 4.0, 0.5, 0.1, static_cast<double>(n), 1e9, 1e-9}) {
        for (uint64_t pixel = 0; pixel < 8; ++pixel) {
          expect_grid_stratification(pattern, n, aspect, {3, pixel, 0, 7});
        }
      }
    }
  }
}

TEST(Patterns, ThinLightsAreStratifiedAlongTheirLength) {
  // aspect >= N: N x 1 strata, so every one of the N columns holds exactly one sample.
  for (Pattern pattern : kGridPatterns) {
    for (uint32_t n : {2u, 5u, 16u, 33u}) {
      std::vector<Vec2> points = points_2d(pattern, {8, 9, 0, 0}, n, 2.0 * n);
      std::vector<int> column_count(n, 0);
      for (const Vec2& p : points) ++column_count[stratum_of(p.x, n)];
      for (int c : column_count) EXPECT_EQ(c, 1) << name_of(pattern) << " n=" << n;
      // The same light turned by 90 degrees: strata along y.
      points = points_2d(pattern, {8, 9, 0, 0}, n, 0.5 / n);
      std::vector<int> row_count(n, 0);
      for (const Vec2& p : points) ++row_count[stratum_of(p.y, n)];
      for (int c : row_count) EXPECT_EQ(c, 1) << name_of(pattern) << " n=" << n;
    }
  }
}

TEST(Patterns, CmjIsAlsoNRooks) {
  // Kensler 2013: the grid samples also fill each of the cells() thin strata of x and of y once.
  for (uint32_t n : {4u, 6u, 12u, 16u, 20u, 64u, 7u, 50u}) {
    for (double aspect : {1.0, 3.0, 0.3}) {
      for (uint64_t pixel = 0; pixel < 16; ++pixel) {
        StrataGrid grid = strata_grid(n, aspect);
        std::vector<Vec2> points = points_2d(Pattern::Cmj, {21, pixel, 1, 0}, n, aspect);
        std::vector<int> x_count(grid.cells(), 0), y_count(grid.cells(), 0);
        for (uint32_t i = 0; i < grid.cells(); ++i) {
          ++x_count[stratum_of(points[i].x, grid.cells())];
          ++y_count[stratum_of(points[i].y, grid.cells())];
        }
        for (uint32_t s = 0; s < grid.cells(); ++s) {
          ASSERT_EQ(x_count[s], 1) << "n=" << n << " aspect=" << aspect;
          ASSERT_EQ(y_count[s], 1) << "n=" << n << " aspect=" << aspect;
        }
      }
    }
  }
}

TEST(Patterns, OneDimensionalGridPatternsPutOneSamplePerStratum) {
  for (Pattern pattern : kGridPatterns) {
    for (uint32_t n : {1u, 2u, 3u, 7u, 10u, 16u, 97u, 1000u}) {
      for (uint64_t pixel = 0; pixel < 8; ++pixel) {
        std::vector<double> line = points_1d(pattern, {4, pixel, 3, 3}, n);
        std::vector<int> count(n, 0);
        for (double v : line) ++count[stratum_of(v, n)];
        for (int c : count) ASSERT_EQ(c, 1) << name_of(pattern) << " n=" << n;
      }
    }
  }
  // Halton and Sobol' in 1D (van der Corput, scrambled): N = 2^k points, one per 1/N stratum.
  for (Pattern pattern : {Pattern::Halton, Pattern::Sobol}) {
    for (uint32_t n : {1u, 2u, 4u, 8u, 64u, 1024u}) {
      std::vector<double> line = points_1d(pattern, {4, 1, 3, 3}, n);
      std::vector<int> count(n, 0);
      for (double v : line) ++count[stratum_of(v, n)];
      for (int c : count) ASSERT_EQ(c, 1) << name_of(pattern) << " n=" << n;
    }
  }
}

TEST(Patterns, UniformIsDeterministicAtStratumCentres) {
  for (uint32_t n : {1u, 4u, 7u, 12u, 16u, 30u}) {
    for (double aspect : {1.0, 2.5, 0.4, 100.0}) {
      StrataGrid grid = strata_grid(n, aspect);
      std::vector<Vec2> a = points_2d(Pattern::Uniform, {1, 2, 3, 4}, n, aspect);
      std::vector<Vec2> b = points_2d(Pattern::Uniform, {99, 98, 97, 96}, n, aspect);
      for (uint32_t i = 0; i < n; ++i) {
        EXPECT_EQ(a[i].x, b[i].x);
        EXPECT_EQ(a[i].y, b[i].y);
        Vec2 centre;
        if (i < grid.cells()) {
          centre = {(i % grid.columns + 0.5) / grid.columns, (i / grid.columns + 0.5) / grid.rows};
        } else {
          double band_centre = (i - grid.cells() + 0.5) / grid.leftover;
          centre = grid.leftover_along_x ? Vec2(band_centre, 0.5) : Vec2(0.5, band_centre);
        }
        EXPECT_NEAR(a[i].x, centre.x, 1e-15);
        EXPECT_NEAR(a[i].y, centre.y, 1e-15);
      }
    }
    std::vector<double> line = points_1d(Pattern::Uniform, {5, 6, 7, 8}, n);
    EXPECT_EQ(line, points_1d(Pattern::Uniform, {50, 60, 70, 80}, n));
    for (uint32_t i = 0; i < n; ++i) EXPECT_NEAR(line[i], (i + 0.5) / n, 1e-15);
  }
}

TEST(Patterns, UniformJitterSharesOneOffsetPerStream) {
  for (uint32_t n : {4u, 9u, 10u, 16u, 21u}) {
    for (double aspect : {1.0, 3.0, 0.25}) {
      StrataGrid grid = strata_grid(n, aspect);
      for (uint64_t pixel = 0; pixel < 20; ++pixel) {
        std::vector<Vec2> points = points_2d(Pattern::UniformJitter, {6, pixel, 0, 2}, n, aspect);
        // The position inside the cell is the same in every cell (cells visited in any order).
        auto offset_in_cell = [&](const Vec2& p) {
          return Vec2(p.x * grid.columns - stratum_of(p.x, grid.columns),
                      p.y * grid.rows - stratum_of(p.y, grid.rows));
        };
        Vec2 offset = offset_in_cell(points[0]);
        for (uint32_t i = 0; i < grid.cells(); ++i) {
          EXPECT_NEAR(offset_in_cell(points[i]).x, offset.x, 1e-12);
          EXPECT_NEAR(offset_in_cell(points[i]).y, offset.y, 1e-12);
        }
        // Leftover bands share it along their length too.
        for (uint32_t i = grid.cells(); i < n; ++i) {
          double along = grid.leftover_along_x ? points[i].x : points[i].y;
          double shared = grid.leftover_along_x ? offset.x : offset.y;
          EXPECT_NEAR(along * grid.leftover - stratum_of(along, grid.leftover), shared, 1e-12);
        }
      }
    }
    // 1D: (i + xi) / N with one xi, different between streams.
    std::vector<double> first = points_1d(Pattern::UniformJitter, {6, 0, 0, 0}, n);
    std::vector<double> second = points_1d(Pattern::UniformJitter, {6, 1, 0, 0}, n);
    double xi = first[0] * n - stratum_of(first[0], n);
    for (uint32_t i = 0; i < n; ++i) EXPECT_NEAR(first[i] * n - stratum_of(first[i], n), xi, 1e-12);
    EXPECT_NE(first[0], second[0]);
  }
}

// The mixture of a pattern's N samples is what an estimator averages, so unbiasedness needs it
// uniform on [0,1)^2. Samples of one stream are dependent (uniform-jitter's all share one offset),
// so each stream contributes one sample with an index drawn independently of the pattern: those
// are independent draws from the mixture, and KS on each marginal and chi-square on 8 x 8 bins of
// the joint apply exactly.
TEST(Patterns, MixtureOfSamplesIsUniform) {
  constexpr uint32_t kStreams = 20000;
  for (Pattern pattern : kRandomizedPatterns) {
    for (uint32_t n : {1u, 4u, 7u, 16u}) {
      for (double aspect : {1.0, 3.0}) {
        std::vector<double> xs, ys;
        std::vector<uint64_t> bins(64, 0);
        for (uint32_t stream = 0; stream < kStreams; ++stream) {
          std::vector<Vec2> points = points_2d(pattern, {12, stream, 0, 5}, n, aspect);
          uint32_t pick = static_cast<uint32_t>(random_uniform({999, stream, 0, 0}, 0, 0) * n);
          xs.push_back(points[pick].x);
          ys.push_back(points[pick].y);
          ++bins[stratum_of(points[pick].y, 8) * 8 + stratum_of(points[pick].x, 8)];
        }
        double critical = testing::ks_critical_0001(kStreams);
        EXPECT_LT(testing::ks_statistic_uniform(xs), critical)
            << name_of(pattern) << " n=" << n << " aspect=" << aspect;
        EXPECT_LT(testing::ks_statistic_uniform(ys), critical)
            << name_of(pattern) << " n=" << n << " aspect=" << aspect;
        EXPECT_LT(testing::chi_square_equal(bins), testing::chi_square_critical_0001(63))
            << name_of(pattern) << " n=" << n << " aspect=" << aspect;
      }
      std::vector<double> line;
      for (uint32_t stream = 0; stream < kStreams; ++stream) {
        uint32_t pick = static_cast<uint32_t>(random_uniform({998, stream, 0, 0}, 0, 0) * n);
        line.push_back(points_1d(pattern, {12, stream, 0, 6}, n)[pick]);
      }
      EXPECT_LT(testing::ks_statistic_uniform(line), testing::ks_critical_0001(kStreams))
          << name_of(pattern) << " 1D n=" << n;
    }
  }
}

// Each sample index on its own, across streams, is uniform over the square for every randomized
// pattern (grid patterns visit their strata in a random order per stream; a scrambled net point
// is uniform): KS on both coordinates of samples 0, 5 and N - 1 (a leftover when N = 7).
TEST(Patterns, EachSampleIndexIsUniform) {
  constexpr uint32_t kStreams = 20000;
  for (Pattern pattern : kRandomizedPatterns) {
    for (uint32_t n : {7u, 8u}) {
      for (uint32_t index : {0u, 5u, n - 1}) {
        std::vector<double> xs, ys, line;
        for (uint32_t stream = 0; stream < kStreams; ++stream) {
          Vec2 p = points_2d(pattern, {13, stream, 0, 0}, n, 1.0)[index];
          xs.push_back(p.x);
          ys.push_back(p.y);
          line.push_back(points_1d(pattern, {13, stream, 0, 1}, n)[index]);
        }
        double critical = testing::ks_critical_0001(kStreams);
        EXPECT_LT(testing::ks_statistic_uniform(xs), critical)
            << name_of(pattern) << " n=" << n << " index " << index;
        EXPECT_LT(testing::ks_statistic_uniform(ys), critical)
            << name_of(pattern) << " n=" << n << " index " << index;
        EXPECT_LT(testing::ks_statistic_uniform(line), critical)
            << name_of(pattern) << " 1D n=" << n << " index " << index;
      }
    }
  }
}

// An estimator may pair sample i of one stream with sample i of another (pixel jitter with light
// sample): the pair must be uniform on the product, or the estimate is biased. Chi-square on 4 x 4
// bins of (x of 2D stream A, 1D stream B) at the same, randomly picked, index.
TEST(Patterns, SameIndexSamplesOfTwoStreamsAreJointlyUniform) {
  constexpr uint32_t kTrials = 20000;
  for (Pattern pattern : kRandomizedPatterns) {
    for (uint32_t n : {4u, 16u}) {
      std::vector<uint64_t> bins(16, 0);
      for (uint32_t trial = 0; trial < kTrials; ++trial) {
        uint32_t pick = static_cast<uint32_t>(random_uniform({997, trial, 0, 0}, 0, 0) * n);
        double a = points_2d(pattern, {14, trial, 0, 0}, n, 1.0)[pick].x;
        double b = points_1d(pattern, {14, trial, 0, 1}, n)[pick];
        ++bins[stratum_of(a, 4) * 4 + stratum_of(b, 4)];
      }
      EXPECT_LT(testing::chi_square_equal(bins), testing::chi_square_critical_0001(15))
          << name_of(pattern) << " n=" << n;
    }
  }
}

// Neighbouring pixels must not share a pattern: the correlation of their first samples is ~0
// (|r| < 4.5 / sqrt(M) over M pixel pairs, i.e. 4.5 standard errors).
TEST(Patterns, NeighbouringPixelsAreDecorrelated) {
  constexpr uint32_t kPairs = 20000;
  const double bound = 4.5 / std::sqrt(static_cast<double>(kPairs));
  for (Pattern pattern : kRandomizedPatterns) {
    for (uint32_t n : {1u, 4u, 16u}) {
      std::vector<double> ax, bx, ay, by, next_pass_x, line_a, line_b;
      for (uint32_t pixel = 0; pixel < kPairs; ++pixel) {
        Vec2 a = points_2d(pattern, {31, pixel, 0, 0}, n, 1.0)[0];
        Vec2 b = points_2d(pattern, {31, pixel + 1, 0, 0}, n, 1.0)[0];
        Vec2 c = points_2d(pattern, {31, pixel, 1, 0}, n, 1.0)[0];
        ax.push_back(a.x);
        ay.push_back(a.y);
        bx.push_back(b.x);
        by.push_back(b.y);
        next_pass_x.push_back(c.x);
        line_a.push_back(points_1d(pattern, {31, pixel, 0, 1}, n)[0]);
        line_b.push_back(points_1d(pattern, {31, pixel + 1, 0, 1}, n)[0]);
      }
      EXPECT_LT(std::abs(testing::correlation(ax, bx)), bound) << name_of(pattern) << " n=" << n;
      EXPECT_LT(std::abs(testing::correlation(ay, by)), bound) << name_of(pattern) << " n=" << n;
      EXPECT_LT(std::abs(testing::correlation(ax, next_pass_x)), bound) << name_of(pattern);
      EXPECT_LT(std::abs(testing::correlation(line_a, line_b)), bound) << name_of(pattern);
    }
  }
}

}  // namespace
}  // namespace penumbra
