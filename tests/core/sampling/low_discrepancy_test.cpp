// Radical inverse, Sobol' direction numbers, Owen scrambling, and the halton / sobol patterns'
// net properties.

#include "core/sampling/low_discrepancy.h"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <vector>

#include "core/sampling/counter_random.h"
#include "core/sampling/pattern.h"
#include "core/sampling/strata.h"
#include "sample_statistics.h"

namespace penumbra {
namespace {

uint64_t power(uint64_t base, int exponent) {
  uint64_t p = 1;
  for (int i = 0; i < exponent; ++i) p *= base;
  return p;
}

// True when points[0..n) put exactly one point in every box [i/bx, (i+1)/bx) x [j/by, (j+1)/by).
bool one_point_per_box(const std::vector<Vec2>& points, uint64_t bx, uint64_t by) {
  std::vector<int> count(bx * by, 0);
  for (const Vec2& p : points) ++count[stratum_of(p.y, by) * bx + stratum_of(p.x, bx)];
  for (int c : count) {
    if (c != 1) return false;
  }
  return true;
}

// A (0,k,2)-net in base 2: for every split k = a + b, one point per 2^-a x 2^-b box.
bool is_base2_net(const std::vector<Vec2>& points, int k) {
  for (int a = 0; a <= k; ++a) {
    if (!one_point_per_box(points, uint64_t{1} << a, uint64_t{1} << (k - a))) return false;
  }
  return true;
}

TEST(RadicalInverse, BaseTwoIsBitReversal) {
  for (uint32_t i = 0; i < 5000; ++i) {
    EXPECT_EQ(radical_inverse(2, i), reverse_bits_32(i) * 0x1.0p-32);
    EXPECT_EQ(reverse_bits_32(reverse_bits_32(i * 2654435761u)), i * 2654435761u);
  }
  EXPECT_EQ(reverse_bits_32(1), 0x80000000u);
  EXPECT_EQ(radical_inverse(3, 1), 1.0 / 3.0);
  EXPECT_EQ(radical_inverse(3, 3), 1.0 / 9.0);
}

TEST(RadicalInverse, FirstPowerOfBasePointsFillTheStrata) {
  for (uint32_t base : {2u, 3u, 5u}) {
    for (int k = 0; k <= 7; ++k) {
      uint64_t n = power(base, k);
      std::vector<int> count(n, 0);
      for (uint64_t i = 0; i < n; ++i) {
        double v = radical_inverse(base, i);
        double scaled = v * static_cast<double>(n);
        EXPECT_NEAR(scaled, std::round(scaled), 1e-9);  // exactly a multiple of 1/n
        ++count[static_cast<uint64_t>(std::round(scaled))];
      }
      for (int c : count) EXPECT_EQ(c, 1) << "base " << base << " k " << k;
    }
  }
}

TEST(Sobol, DirectionNumbersFollowTheRecurrence) {
  // The direction numbers are the images of the powers of two; m_k = v_k 2^k must be odd, below
  // 2^k, and satisfy m_k = 2 m_{k-1} xor m_{k-1} (polynomial x + 1).
  uint32_t previous_m = 0;
  for (int k = 1; k <= 32; ++k) {
    uint32_t v = sobol_bits(uint32_t{1} << (k - 1), 1);
    uint64_t m = uint64_t{v} >> (32 - k);
    EXPECT_EQ(m << (32 - k), uint64_t{v}) << k;  // no bits below 2^-k
    EXPECT_EQ(m & 1, 1u) << k;
    if (k > 1) {
      EXPECT_EQ(m, (uint64_t{previous_m} << 1) ^ previous_m) << k;
    }
    previous_m = static_cast<uint32_t>(m);
  }
  EXPECT_EQ(sobol_bits(1, 1) >> 30, 2u);  // m_1 = 1: v_1 = 1/2
}

TEST(Sobol, UnscrambledFirstTwoDimensionsAreA02Sequence) {
  // Every prefix of 2^k points is a (0,k,2)-net, and so is every aligned block of 2^k points.
  for (int k = 0; k <= 12; ++k) {
    uint32_t n = uint32_t{1} << k;
    for (uint32_t block : {0u, 1u, 5u}) {
      std::vector<Vec2> points;
      for (uint32_t i = block * n; i < (block + 1) * n; ++i) {
        points.push_back({sobol_bits(i, 0) * 0x1.0p-32, sobol_bits(i, 1) * 0x1.0p-32});
      }
      EXPECT_TRUE(is_base2_net(points, k)) << "k " << k << " block " << block;
    }
  }
}

TEST(OwenScrambling, BaseTwoRoundTripsAndIsABijection) {
  StreamRandom rng({1, 1, 1, 1});
  for (int levels = 0; levels <= 32; ++levels) {
    for (uint32_t t = 0; t < 500; ++t) {
      uint64_t seed = rng.bits(t, 0);
      uint32_t bits = static_cast<uint32_t>(rng.bits(t, 1));
      uint32_t scrambled = owen_scramble_base2(bits, levels, seed);
      EXPECT_EQ(owen_unscramble_base2(scrambled, levels, seed), bits);
      // Bits below `levels` pass through.
      uint64_t low_mask = (uint64_t{1} << (32 - levels)) - 1;
      EXPECT_EQ(scrambled & low_mask, bits & low_mask);
    }
  }
}

TEST(OwenScrambling, BaseTwoIsNested) {
  // Nested scrambling keeps the length of the common leading-digit prefix of any two points.
  StreamRandom rng({2, 2, 2, 2});
  for (uint32_t t = 0; t < 20000; ++t) {
    uint64_t seed = rng.bits(t, 0);
    uint32_t a = static_cast<uint32_t>(rng.bits(t, 1));
    uint32_t b = a ^ (uint32_t{1} << (rng.bits(t, 2) % 32));     // differ first at a random digit
    b ^= static_cast<uint32_t>(rng.bits(t, 3)) & ((a ^ b) - 1);  // and anywhere below it
    int common = std::countl_zero(a ^ b);
    uint32_t sa = owen_scramble_base2(a, 32, seed);
    uint32_t sb = owen_scramble_base2(b, 32, seed);
    EXPECT_EQ(std::countl_zero(sa ^ sb), common);
  }
}

TEST(OwenScrambling, DigitFlipsAreFairAndIndependentBetweenNodes) {
  // The flips of the first digit and of the two second-level nodes, over many seeds: each of the
  // 8 combinations has probability 1/8 (chi-square, 7 dof, critical 24.3 at 0.001).
  std::vector<uint64_t> combos(8, 0);
  StreamRandom rng({3, 3, 3, 3});
  for (uint32_t t = 0; t < 40000; ++t) {
    uint64_t seed = rng.bits(t, 0);
    uint32_t first = owen_scramble_base2(0u, 1, seed) >> 31;
    uint32_t left = (owen_scramble_base2(0u, 2, seed) >> 30) & 1;
    uint32_t right = (owen_scramble_base2(0x80000000u, 2, seed) >> 30) & 1;
    ++combos[first * 4 + left * 2 + right];
  }
  EXPECT_LT(testing::chi_square_equal(combos), 24.32);
}

TEST(OwenScrambling, BaseThreeRoundTripsAndPermutesDigits) {
  StreamRandom rng({4, 4, 4, 4});
  for (int levels = 0; levels <= 12; ++levels) {
    uint64_t strata = power(3, levels);
    for (uint32_t t = 0; t < 50; ++t) {
      uint64_t seed = rng.bits(t, 0);
      // The first 3^levels indices map to all 3^levels digit strings exactly once.
      if (levels <= 7) {
        std::vector<int> hit(strata, 0);
        for (uint64_t i = 0; i < strata; ++i) {
          uint64_t scrambled = owen_scramble_base3(i, levels, seed);
          ASSERT_LT(scrambled, strata);
          ++hit[scrambled];
          ASSERT_EQ(owen_unscramble_base3(scrambled, levels, seed), i);
        }
        for (int h : hit) ASSERT_EQ(h, 1);
      }
      uint64_t index = rng.bits(t, 1) >> 20;
      EXPECT_EQ(owen_unscramble_base3(owen_scramble_base3(index, levels, seed), levels, seed),
                index % strata);
    }
  }
}

TEST(OwenScrambling, BaseThreePermutationsAreUniform) {
  // The first digit of index 0 (node at the root) takes each value with probability 1/3, and the
  // pair (root digit of 0, root digit of 1) is one of the 6 ordered distinct pairs uniformly.
  std::vector<uint64_t> pairs(9, 0);
  StreamRandom rng({5, 5, 5, 5});
  for (uint32_t t = 0; t < 30000; ++t) {
    uint64_t seed = rng.bits(t, 0);
    ++pairs[owen_scramble_base3(0, 1, seed) * 3 + owen_scramble_base3(1, 1, seed)];
  }
  for (int same = 0; same < 3; ++same) EXPECT_EQ(pairs[same * 4], 0u);
  std::vector<uint64_t> distinct = {pairs[1], pairs[2], pairs[3], pairs[5], pairs[6], pairs[7]};
  EXPECT_LT(testing::chi_square_equal(distinct), 20.52);  // 5 dof at 0.001
}

TEST(HaltonPattern, FirstPointsUnscrambleToTheHaltonSequence) {
  for (uint32_t n : {1u, 2u, 5u, 16u, 27u, 100u}) {
    for (uint64_t pixel = 0; pixel < 10; ++pixel) {
      StreamKey key{9, pixel, 1, 3};
      std::vector<Vec2> points(n);
      generate_2d(Pattern::Halton, key, 1.0, points);
      int levels2 = digits_to_separate(2, n);
      int levels3 = digits_to_separate(3, n);
      uint64_t seed_x = owen_seed(key, 0);
      uint64_t seed_y = owen_seed(key, 1);
      for (uint32_t i = 0; i < n; ++i) {
        // Base 2: the first levels2 digits of x.
        uint32_t top = static_cast<uint32_t>(stratum_of(points[i].x, uint64_t{1} << levels2));
        uint32_t digits = levels2 == 0 ? 0 : top << (32 - levels2);
        uint32_t unscrambled = owen_unscramble_base2(digits, levels2, seed_x);
        EXPECT_EQ(unscrambled, levels2 == 0 ? 0 : reverse_bits_32(i));
        // Base 3: the first levels3 digits of y are the digits of i.
        uint64_t stratum = stratum_of(points[i].y, power(3, levels3));
        EXPECT_EQ(owen_unscramble_base3(stratum, levels3, seed_y), i);
        // And the unscrambled first digits are those of the radical inverses.
        EXPECT_NEAR(unscrambled * 0x1.0p-32, radical_inverse(2, i), 1e-15);
      }
    }
  }
}

TEST(HaltonPattern, FirstTwoToTheAThreeToTheBPointsFillEveryBox) {
  for (int a = 0; a <= 5; ++a) {
    for (int b = 0; b <= 3; ++b) {
      uint64_t bx = power(2, a), by = power(3, b);
      for (uint64_t pixel = 0; pixel < 10; ++pixel) {
        std::vector<Vec2> points(bx * by);
        generate_2d(Pattern::Halton, {10, pixel, 0, 0}, 1.0, points);
        EXPECT_TRUE(one_point_per_box(points, bx, by)) << "2^" << a << " 3^" << b;
      }
    }
  }
}

TEST(SobolPattern, PowerOfTwoCountsAre02Nets) {
  for (int k = 0; k <= 10; ++k) {
    for (uint64_t pixel = 0; pixel < 10; ++pixel) {
      std::vector<Vec2> points(size_t{1} << k);
      generate_2d(Pattern::Sobol, {11, pixel, 2, 0}, 1.0, points);
      EXPECT_TRUE(is_base2_net(points, k)) << "k " << k;
    }
  }
}

TEST(SobolPattern, FirstPointsUnscrambleToTheSobolSequence) {
  for (uint32_t n : {1u, 2u, 3u, 8u, 13u, 64u}) {
    for (uint64_t pixel = 0; pixel < 10; ++pixel) {
      StreamKey key{12, pixel, 0, 4};
      std::vector<Vec2> points(n);
      generate_2d(Pattern::Sobol, key, 1.0, points);
      int levels = digits_to_separate(2, n);
      for (uint32_t i = 0; i < n && levels > 0; ++i) {
        for (int d = 0; d < 2; ++d) {
          uint32_t top = static_cast<uint32_t>(stratum_of(points[i][d], uint64_t{1} << levels));
          uint32_t unscrambled = owen_unscramble_base2(top << (32 - levels), levels,
                                                       owen_seed(key, static_cast<uint32_t>(d)));
          EXPECT_EQ(unscrambled, sobol_bits(i, d)) << "n " << n << " i " << i << " d " << d;
        }
      }
    }
  }
}

TEST(LowDiscrepancyPatterns, LargeCountsKeepTheirNets) {
  // Beyond 2^16 (base 2) and 3^10 (base 3) points the patterns scramble point by point instead of
  // through per-stream tables: the nets must survive the switch.
  uint32_t n = uint32_t{1} << 17;
  std::vector<Vec2> points(n);
  generate_2d(Pattern::Sobol, {14, 0, 0, 0}, 1.0, points);
  EXPECT_TRUE(is_base2_net(points, 17));
  uint64_t strata3 = power(3, 11);
  points.resize(strata3);
  generate_2d(Pattern::Halton, {14, 1, 0, 0}, 1.0, points);
  std::vector<int> count(strata3, 0);
  for (const Vec2& p : points) ++count[stratum_of(p.y, strata3)];
  for (int c : count) ASSERT_EQ(c, 1);
  // The first 2^17 Halton points in x (base 2; 3^11 > 2^17).
  points.resize(n);
  generate_2d(Pattern::Halton, {14, 2, 0, 0}, 1.0, points);
  count.assign(n, 0);
  for (const Vec2& p : points) ++count[stratum_of(p.x, n)];
  for (int c : count) ASSERT_EQ(c, 1);
}

TEST(SobolPattern, ScramblingChangesThePointsBetweenStreams) {
  // Without scrambling every stream would start at (0, 0).
  std::vector<double> first_x;
  for (uint64_t pixel = 0; pixel < 2000; ++pixel) {
    std::vector<Vec2> points(4);
    generate_2d(Pattern::Sobol, {13, pixel, 0, 0}, 1.0, points);
    first_x.push_back(points[0].x);
  }
  EXPECT_LT(testing::ks_statistic_uniform(first_x), testing::ks_critical_0001(first_x.size()));
}

}  // namespace
}  // namespace penumbra
