#include "core/render/tile.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

namespace penumbra {
namespace {

TEST(FixedPoint, RoundTripsWithinTheQuantum) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> exponent(-8, 8);
  for (int i = 0; i < 100000; ++i) {
    double v = std::pow(10.0, exponent(rng)) * (i % 3 == 0 ? -1 : 1);
    EXPECT_NEAR(from_fixed(to_fixed(v)), v, std::ldexp(1.0, -32) + std::abs(v) * 1e-15) << v;
  }
  EXPECT_EQ(from_fixed(to_fixed(0.0)), 0.0);
  EXPECT_EQ(from_fixed(to_fixed(1.5)), 1.5);
  EXPECT_EQ(from_fixed(to_fixed(-2.25)), -2.25);
}

TileAccumulator random_passes(const TileRect& rect, int begin, int end) {
  TileAccumulator tile(rect);
  for (int pass = begin; pass < end; ++pass) {
    std::mt19937_64 rng(1000 + pass);  // a pass's samples do not depend on the split
    std::exponential_distribution<double> value(0.5);
    for (int64_t i = 0; i < rect.pixel_count(); ++i)
      tile.add_sample(i, {value(rng), value(rng) * 1e-4, value(rng) * 1e3});
  }
  return tile;
}

TEST(TileAccumulator, MergeIsExactWhateverTheSplitAndOrder) {
  TileRect rect{8, 16, 24, 28};
  TileAccumulator whole = random_passes(rect, 0, 32);

  // Split into uneven pass ranges and merge them in a shuffled order.
  std::vector<std::pair<int, int>> ranges{{0, 3}, {3, 4}, {4, 17}, {17, 20}, {20, 32}};
  std::mt19937 shuffle_rng(3);
  for (int attempt = 0; attempt < 5; ++attempt) {
    std::shuffle(ranges.begin(), ranges.end(), shuffle_rng);
    TileAccumulator merged(rect);
    for (auto [b, e] : ranges) merged.merge(random_passes(rect, b, e));
    EXPECT_TRUE(merged == whole);
    for (int64_t i = 0; i < rect.pixel_count(); ++i) {
      EXPECT_EQ(merged.count(i), 32u);
      Rgb a = merged.mean(i), b = whole.mean(i);
      EXPECT_EQ(a.x, b.x);
      EXPECT_EQ(a.y, b.y);
      EXPECT_EQ(a.z, b.z);
    }
  }
}

TEST(TileAccumulator, MeanAndVarianceOfTheMeanMatchTheDefinition) {
  TileRect rect{0, 0, 1, 1};
  TileAccumulator tile(rect);
  std::vector<double> values{0.5, 1.5, 2.0, 4.0, 0.25};
  for (double v : values) tile.add_sample(0, {v, 2 * v, 0});
  double mean = 0;
  for (double v : values) mean += v;
  mean /= values.size();
  double var = 0;
  for (double v : values) var += (v - mean) * (v - mean);
  var /= values.size() - 1;
  EXPECT_NEAR(tile.mean(0).x, mean, 1e-9);
  EXPECT_NEAR(tile.mean(0).y, 2 * mean, 1e-9);
  EXPECT_NEAR(tile.variance_of_mean(0).x, var / values.size(), 1e-8);
  EXPECT_NEAR(tile.variance_of_mean(0).y, 4 * var / values.size(), 1e-8);
  EXPECT_EQ(tile.variance_of_mean(0).z, 0.0);
}

TEST(TileAccumulator, NonFiniteSamplesAreCountedNotSummed) {
  TileAccumulator tile({0, 0, 2, 1});
  tile.add_sample(0, {NAN, 1, INFINITY});
  tile.add_sample(0, {1, 1, 1});
  EXPECT_EQ(tile.nonfinite_samples(), 2u);
  EXPECT_TRUE(std::isfinite(tile.mean(0).x));
  EXPECT_DOUBLE_EQ(tile.mean(0).x, 0.5);
}

TEST(TileAccumulator, SerializesExactlyAndRejectsBadBytes) {
  TileRect rect{64, 0, 128, 40};
  TileAccumulator tile = random_passes(rect, 0, 3);
  std::string bytes = tile.serialize();
  EXPECT_TRUE(TileAccumulator::deserialize(bytes) == tile);

  EXPECT_THROW(TileAccumulator::deserialize(""), std::invalid_argument);
  EXPECT_THROW(TileAccumulator::deserialize(bytes.substr(0, bytes.size() - 1)),
               std::invalid_argument);
  std::string bad_magic = bytes;
  bad_magic[0] ^= 0x55;
  EXPECT_THROW(TileAccumulator::deserialize(bad_magic), std::invalid_argument);
  std::string bad_rect = bytes;
  bad_rect[4 + 8] = 0;  // x1 = 0 < x0
  bad_rect[4 + 9] = 0;
  EXPECT_THROW(TileAccumulator::deserialize(bad_rect), std::invalid_argument);
  TileAccumulator other({0, 0, 4, 4});
  EXPECT_THROW(other.merge(tile), std::invalid_argument);
}

// A result whose sums no sample could produce (each sample is clamped to 2^60, so a pixel's sums
// stay within count * 2^92 in 2^-32 fixed point) is refused: merging it could overflow.
TEST(TileAccumulator, RejectsSumsNoSampleCouldProduce) {
  TileRect rect{0, 0, 2, 1};
  TileAccumulator tile(rect);
  tile.add_sample(0, {1e30, -1e30, 1e30});  // clamped to +-2^60: still a valid tile
  tile.add_sample(1, {0.5, 0.5, 0.5});
  std::string bytes = tile.serialize();
  ASSERT_TRUE(TileAccumulator::deserialize(bytes) == tile);
  // Layout: 28-byte header, then 6 sums and 6 squares (16 bytes each), then the counts.
  auto with_value = [&](size_t slot, Fixed128 value) {
    std::string b = bytes;
    std::memcpy(b.data() + 28 + 16 * slot, &value, sizeof value);
    return b;
  };
  const Fixed128 beyond = (Fixed128(1) << 92) + 1;  // one sample's bound, plus one quantum
  EXPECT_THROW(TileAccumulator::deserialize(with_value(0, beyond)), std::invalid_argument);
  EXPECT_THROW(TileAccumulator::deserialize(with_value(1, -beyond)), std::invalid_argument);
  EXPECT_THROW(TileAccumulator::deserialize(with_value(6, -1)), std::invalid_argument);  // square
  EXPECT_NO_THROW(TileAccumulator::deserialize(with_value(0, Fixed128(1) << 92)));
}

}  // namespace
}  // namespace penumbra
