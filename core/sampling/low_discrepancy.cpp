#include "core/sampling/low_discrepancy.h"

#include <algorithm>
#include <array>

#include "core/sampling/counter_random.h"

namespace penumbra {

namespace {

// Sobol' dimension 1: direction number v_k = m_k / 2^k for index bit k-1, as 0.32 fractions.
// Primitive polynomial x + 1 has degree s = 1 and no inner coefficients, so Bratley & Fox's
// recurrence m_k = 2^s m_{k-s} xor m_{k-s} becomes m_k = 2 m_{k-1} xor m_{k-1}, with m_1 = 1:
// m = 1, 3, 5, 15, 17, 51, ... (each m_k odd and below 2^k, as direction numbers must be).
constexpr std::array<uint32_t, 32> make_sobol_dimension1_directions() {
  std::array<uint32_t, 32> directions{};
  uint32_t m = 1;
  for (int k = 1; k <= 32; ++k) {
    if (k > 1) m = (m << 1) ^ m;
    directions[k - 1] = m << (32 - k);
  }
  return directions;
}
constexpr std::array<uint32_t, 32> kSobolDimension1 = make_sobol_dimension1_directions();

constexpr uint64_t kGolden = 0x9e3779b97f4a7c15ull;
constexpr uint64_t kBase3Salt = 0x2545f4914f6cdd1dull;
// Stream draws that seed Owen scrambling use dimensions from here on.
constexpr uint32_t kOwenSeedDimension = 0x100;

// The six permutations of {0,1,2} and their inverses.
constexpr uint8_t kPermutations3[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2},
                                          {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
constexpr uint8_t kInversePermutations3[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2},
                                                 {2, 0, 1}, {1, 2, 0}, {2, 1, 0}};

}  // namespace

double radical_inverse(uint32_t base, uint64_t index) {
  uint64_t reversed = 0;
  double denominator = 1.0;
  while (index > 0) {
    reversed = reversed * base + index % base;
    denominator *= base;
    index /= base;
  }
  return static_cast<double>(reversed) / denominator;
}

uint32_t sobol_bits(uint32_t index, int dimension) {
  if (dimension == 0) return reverse_bits_32(index);
  uint32_t bits = 0;
  for (int k = 0; index != 0; ++k, index >>= 1) {
    if (index & 1u) bits ^= kSobolDimension1[k];
  }
  return bits;
}

int digits_to_separate(uint32_t base, uint64_t n) {
  int digits = 0;
  for (uint64_t reach = 1; reach < n; reach *= base) ++digits;
  return digits;
}

uint64_t owen_seed(const StreamRandom& stream, uint32_t dimension) {
  return stream.bits(kStreamDrawSample, kOwenSeedDimension + dimension);
}

uint64_t owen_seed(const StreamKey& key, uint32_t dimension) {
  return owen_seed(StreamRandom(key), dimension);
}

OwenScramblerBase2::OwenScramblerBase2(uint64_t seed, int levels, bool keep_words)
    : seed_(seed), levels_(levels) {
  // Node ids of `levels` levels are below 2^levels: 64 per word.
  uint64_t words_needed = levels <= 0 ? 0 : ((uint64_t{1} << levels) + 63) >> 6;
  kept_ = keep_words ? static_cast<uint32_t>(std::min<uint64_t>(words_needed, kKeptWords)) : 0;
  for (uint32_t i = 0; i < kept_; ++i) words_[i] = word(i);
}

uint64_t OwenScramblerBase2::word(uint64_t index) const {
  return mix_bits(seed_ ^ (index * kGolden));
}

OwenScramblerBase3::OwenScramblerBase3(uint64_t seed, int levels, bool keep_words)
    : seed_(seed), levels_(levels) {
  // Node ids of `levels` levels are below (3^levels - 1) / 2: 2 per word.
  uint64_t nodes = 0;
  uint64_t place = 1;
  for (int level = 0; level < levels && nodes < 2 * kKeptWords; ++level, place *= 3) {
    nodes += place;
  }
  uint64_t words_needed = (nodes + 1) / 2;
  kept_ = keep_words ? static_cast<uint32_t>(std::min<uint64_t>(words_needed, kKeptWords)) : 0;
  for (uint32_t i = 0; i < kept_; ++i) words_[i] = word(i);
}

uint64_t OwenScramblerBase3::word(uint64_t index) const {
  return mix_bits(seed_ ^ kBase3Salt ^ (index * kGolden));
}

uint64_t OwenScramblerBase3::scramble(uint64_t index) const {
  uint64_t scrambled_digits = 0;
  uint64_t prefix = 0;     // index mod 3^level
  uint64_t place = 1;      // 3^level
  uint64_t level_ids = 0;  // id of the first node of this level, (3^level - 1) / 2
  for (int level = 0; level < levels_; ++level) {
    uint32_t digit = static_cast<uint32_t>(index % 3);
    index /= 3;
    int chosen = permutation(level_ids + prefix);
    scrambled_digits = scrambled_digits * 3 + kPermutations3[chosen][digit];
    prefix += digit * place;
    level_ids += place;
    place *= 3;
  }
  return scrambled_digits;
}

uint64_t OwenScramblerBase3::unscramble(uint64_t scrambled_digits) const {
  uint64_t top_place = 1;
  for (int level = 1; level < levels_; ++level) top_place *= 3;
  uint64_t prefix = 0;
  uint64_t place = 1;
  uint64_t level_ids = 0;
  for (int level = 0; level < levels_; ++level) {
    uint32_t scrambled = static_cast<uint32_t>((scrambled_digits / top_place) % 3);
    top_place /= 3;
    int chosen = permutation(level_ids + prefix);
    prefix += kInversePermutations3[chosen][scrambled] * place;
    level_ids += place;
    place *= 3;
  }
  return prefix;
}

void OwenScramblerBase2::fill_table(std::span<uint32_t> table) const {
  // Level by level, in place: entry p of the first k digits (digit 0 on top) splits into entries
  // 2p and 2p + 1 at digit k, flipped by node (k, p). Descending p never overwrites an entry
  // before it is read.
  table[0] = 0;
  for (int level = 0; level < levels_; ++level) {
    uint64_t level_ids = uint64_t{1} << level;
    for (uint64_t p = level_ids; p-- > 0;) {
      uint32_t flipped = flip(level_ids | p);
      uint32_t parent = table[p] << 1;
      table[2 * p] = parent | flipped;
      table[2 * p + 1] = parent | (flipped ^ 1u);
    }
  }
}

void OwenScramblerBase3::fill_table(std::span<uint64_t> table) const {
  // As in base 2, in place: entry i < 3^k splits into i, i + 3^k, i + 2 3^k at digit k. The node
  // of digit k of index i is i mod 3^k, the entry itself.
  table[0] = 0;
  uint64_t place = 1;
  uint64_t level_ids = 0;
  for (int level = 0; level < levels_; ++level) {
    for (uint64_t i = 0; i < place; ++i) {
      const uint8_t* chosen = kPermutations3[permutation(level_ids + i)];
      uint64_t parent = table[i] * 3;
      table[i] = parent + chosen[0];
      table[i + place] = parent + chosen[1];
      table[i + 2 * place] = parent + chosen[2];
    }
    level_ids += place;
    place *= 3;
  }
}

uint32_t owen_scramble_base2(uint32_t bits, int levels, uint64_t seed) {
  return OwenScramblerBase2(seed, levels, false).scramble(bits);
}

uint32_t owen_unscramble_base2(uint32_t scrambled, int levels, uint64_t seed) {
  return OwenScramblerBase2(seed, levels, false).unscramble(scrambled);
}

uint64_t owen_scramble_base3(uint64_t index, int levels, uint64_t seed) {
  return OwenScramblerBase3(seed, levels, false).scramble(index);
}

uint64_t owen_unscramble_base3(uint64_t scrambled_digits, int levels, uint64_t seed) {
  return OwenScramblerBase3(seed, levels, false).unscramble(scrambled_digits);
}

}  // namespace penumbra
