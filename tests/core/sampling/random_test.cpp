// The counter-based generator: a pure function of its key, sensitive to every field, uniform.

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <set>
#include <vector>

#include "core/sampling/counter_random.h"
#include "core/sampling/pattern.h"
#include "sample_statistics.h"

namespace penumbra {
namespace {

StreamKey key_number(uint64_t i) {
  // Keys spread over all fields, including large values.
  return StreamKey{i * 0x9e3779b9ull, i * 7919 + (i << 40), static_cast<uint32_t>(i * 31),
                   static_cast<uint32_t>(i % 5)};
}

TEST(RandomBits, SameKeyGivesSameBits) {
  for (uint64_t i = 0; i < 1000; ++i) {
    StreamKey key = key_number(i);
    StreamKey copy = key;
    uint32_t sample = static_cast<uint32_t>(i * 13);
    uint32_t dimension = static_cast<uint32_t>(i % 7);
    EXPECT_EQ(random_bits(key, sample, dimension), random_bits(copy, sample, dimension));
    EXPECT_EQ(random_bits(key, sample, dimension), StreamRandom(key).bits(sample, dimension));
    EXPECT_EQ(random_uniform(key, sample, dimension), random_uniform(copy, sample, dimension));
  }
}

TEST(RandomBits, EveryFieldChangesTheBits) {
  // Changing any one field of (seed, pixel, pass, stream, sample, dimension) must change the
  // output: by construction it always does (each absorption step is a bijection), so any
  // collision here is a bug.
  for (uint64_t i = 0; i < 2000; ++i) {
    StreamKey key = key_number(i);
    uint32_t sample = static_cast<uint32_t>(i);
    uint32_t dimension = static_cast<uint32_t>(i % 3);
    uint64_t base = random_bits(key, sample, dimension);
    for (uint64_t delta : {uint64_t{1}, uint64_t{2}, uint64_t{1} << 31, uint64_t{0xffff}}) {
      StreamKey k = key;
      k.seed += delta;
      EXPECT_NE(random_bits(k, sample, dimension), base);
      k = key;
      k.pixel += delta;
      EXPECT_NE(random_bits(k, sample, dimension), base);
      k = key;
      k.pass += static_cast<uint32_t>(delta);
      EXPECT_NE(random_bits(k, sample, dimension), base);
      k = key;
      k.stream += static_cast<uint32_t>(delta);
      EXPECT_NE(random_bits(k, sample, dimension), base);
      EXPECT_NE(random_bits(key, sample + static_cast<uint32_t>(delta), dimension), base);
      EXPECT_NE(random_bits(key, sample, dimension + static_cast<uint32_t>(delta)), base);
    }
  }
}

TEST(RandomBits, NoCollisionsOverManyCounters) {
  std::set<uint64_t> seen;
  StreamKey key{42, 0, 0, 0};
  for (uint32_t pixel = 0; pixel < 64; ++pixel) {
    key.pixel = pixel;
    for (uint32_t sample = 0; sample < 64; ++sample) {
      for (uint32_t dimension = 0; dimension < 8; ++dimension) {
        seen.insert(random_bits(key, sample, dimension));
      }
    }
  }
  EXPECT_EQ(seen.size(), 64u * 64u * 8u);
}

// Strict avalanche: flipping one input bit of any field flips each output bit with probability
// 1/2. Over 4000 trials the flip rate of every (input bit, output bit) pair lies in
// 0.5 +- 0.0395 (5 standard deviations; 64 x 64 x 6 pairs make a 5-sigma miss unlikely).
TEST(RandomBits, AvalancheOnEveryField) {
  constexpr int kTrials = 4000;
  const double tolerance = 5.0 * 0.5 / std::sqrt(static_cast<double>(kTrials));
  for (int field = 0; field < 6; ++field) {
    int input_bits = field == 0 || field == 1 ? 64 : 32;
    for (int input_bit = 0; input_bit < input_bits; input_bit += 3) {
      std::vector<int> flips(64, 0);
      for (int trial = 0; trial < kTrials; ++trial) {
        StreamKey key{random_bits({7, 1, 0, 0}, trial, 0), random_bits({7, 1, 0, 0}, trial, 1),
                      static_cast<uint32_t>(random_bits({7, 1, 0, 0}, trial, 2)),
                      static_cast<uint32_t>(random_bits({7, 1, 0, 0}, trial, 3))};
        uint32_t sample = static_cast<uint32_t>(random_bits({7, 1, 0, 0}, trial, 4));
        uint32_t dimension = static_cast<uint32_t>(random_bits({7, 1, 0, 0}, trial, 5));
        uint64_t before = random_bits(key, sample, dimension);
        uint64_t flip = uint64_t{1} << input_bit;
        switch (field) {
          case 0:
            key.seed ^= flip;
            break;
          case 1:
            key.pixel ^= flip;
            break;
          case 2:
            key.pass ^= static_cast<uint32_t>(flip);
            break;
          case 3:
            key.stream ^= static_cast<uint32_t>(flip);
            break;
          case 4:
            sample ^= static_cast<uint32_t>(flip);
            break;
          default:
            dimension ^= static_cast<uint32_t>(flip);
            break;
        }
        uint64_t changed = before ^ random_bits(key, sample, dimension);
        for (int out = 0; out < 64; ++out) flips[out] += (changed >> out) & 1;
      }
      for (int out = 0; out < 64; ++out) {
        double rate = flips[out] / static_cast<double>(kTrials);
        EXPECT_NEAR(rate, 0.5, tolerance)
            << "field " << field << " input bit " << input_bit << " output bit " << out;
      }
    }
  }
}

TEST(RandomUniform, HasFiftyThreeBitsInUnitInterval) {
  StreamKey key{3, 4, 5, 6};
  int odd_last_bit = 0;
  constexpr int kCount = 100000;
  for (uint32_t i = 0; i < kCount; ++i) {
    double u = random_uniform(key, i, 0);
    ASSERT_GE(u, 0.0);
    ASSERT_LT(u, 1.0);
    double scaled = u * 0x1.0p53;
    ASSERT_EQ(scaled, std::floor(scaled));  // a multiple of 2^-53
    odd_last_bit += static_cast<uint64_t>(scaled) & 1;
  }
  // The 53rd bit is random: half of the values have it set (5 sigma: +- 791).
  EXPECT_NEAR(odd_last_bit, kCount / 2, 5 * std::sqrt(kCount / 4.0));
  EXPECT_EQ(bits_to_unit_double(~uint64_t{0}), kOneMinusEpsilon);
  EXPECT_EQ(bits_to_unit_double(0), 0.0);
}

TEST(RandomUniform, KolmogorovSmirnovAcrossSamplesAndPixels) {
  // Counters vary along the sample axis in one pass, along the pixel axis in the other.
  constexpr uint32_t kCount = 200000;
  std::vector<double> along_samples, along_pixels;
  for (uint32_t i = 0; i < kCount; ++i) {
    along_samples.push_back(random_uniform({11, 0, 0, 0}, i, 0));
    along_pixels.push_back(random_uniform({11, i, 0, 0}, 0, 0));
  }
  double critical = testing::ks_critical_0001(kCount);  // 0.00436
  EXPECT_LT(testing::ks_statistic_uniform(along_samples), critical);
  EXPECT_LT(testing::ks_statistic_uniform(along_pixels), critical);
}

TEST(RandomUniform, ChiSquareOfPairsOn2DBins) {
  // Consecutive dimensions of one sample are the pairs a 2D pattern uses.
  constexpr int kBins = 32;
  constexpr uint32_t kPairs = 1u << 20;
  std::vector<uint64_t> counts(kBins * kBins, 0);
  StreamKey key{5, 77, 1, 2};
  StreamRandom rng(key);
  for (uint32_t i = 0; i < kPairs; ++i) {
    int bx = static_cast<int>(rng.uniform(i, 0) * kBins);
    int by = static_cast<int>(rng.uniform(i, 1) * kBins);
    ++counts[by * kBins + bx];
  }
  double chi2 = testing::chi_square_equal(counts);
  EXPECT_LT(chi2, testing::chi_square_critical_0001(kBins * kBins - 1));  // ~1168
  // An independent generator would not be this far under either (chi-square's 0.1% lower tail).
  EXPECT_GT(chi2, 870.0);
}

TEST(RandomUniform, ChiSquareOfNeighbouringPixelsOn2DBins) {
  // The first draw of pixel p against that of pixel p + 1: independent means uniform on the square.
  constexpr int kBins = 16;
  constexpr uint32_t kPixels = 1u << 18;
  std::vector<uint64_t> counts(kBins * kBins, 0);
  for (uint32_t p = 0; p < kPixels; ++p) {
    int bx = static_cast<int>(random_uniform({9, p, 0, 0}, 0, 0) * kBins);
    int by = static_cast<int>(random_uniform({9, p + 1, 0, 0}, 0, 0) * kBins);
    ++counts[by * kBins + bx];
  }
  EXPECT_LT(testing::chi_square_equal(counts),
            testing::chi_square_critical_0001(kBins * kBins - 1));
}

}  // namespace
}  // namespace penumbra
