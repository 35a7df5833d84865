#include "core/sampling/low_discrepancy.h"

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

// The random flip of the base-2 digit at tree node (level, prefix): 0 or 1.
inline uint32_t base2_node_flip(uint64_t seed, int level, uint64_t prefix) {
  uint64_t node = (uint64_t{1} << level) | prefix;  // unique per (level, prefix)
  return static_cast<uint32_t>(mix_bits(seed ^ (node * kGolden)) >> 63);
}

// The random permutation (index into kPermutations3) of the base-3 digit at node (level, prefix).
inline int base3_node_permutation(uint64_t seed, int level, uint64_t prefix) {
  uint64_t node = (static_cast<uint64_t>(level) << 56) ^ prefix;  // prefix < 3^32 < 2^56
  return static_cast<int>(mix_bits(seed ^ kBase3Salt ^ (node * kGolden)) % 6);
}

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

uint64_t owen_seed(const StreamKey& key, uint32_t dimension) {
  return StreamRandom(key).bits(kStreamDrawSample, kOwenSeedDimension + dimension);
}

uint32_t owen_scramble_base2(uint32_t bits, int levels, uint64_t seed) {
  uint32_t scrambled = bits;
  for (int level = 0; level < levels; ++level) {
    uint64_t prefix = level == 0 ? 0 : bits >> (32 - level);
    scrambled ^= base2_node_flip(seed, level, prefix) << (31 - level);
  }
  return scrambled;
}

uint32_t owen_unscramble_base2(uint32_t scrambled, int levels, uint64_t seed) {
  // Restore the digits from the top: each flip depends only on the digits above it.
  uint32_t bits = scrambled;
  for (int level = 0; level < levels; ++level) {
    uint64_t prefix = level == 0 ? 0 : bits >> (32 - level);
    bits ^= base2_node_flip(seed, level, prefix) << (31 - level);
  }
  return bits;
}

uint64_t owen_scramble_base3(uint64_t index, int levels, uint64_t seed) {
  // Digit k of the radical inverse is digit k of the index (least significant first); the node
  // of digit k is the index modulo 3^k.
  uint64_t scrambled_digits = 0;
  uint64_t prefix = 0;
  uint64_t place = 1;
  for (int level = 0; level < levels; ++level) {
    uint32_t digit = static_cast<uint32_t>(index % 3);
    index /= 3;
    int permutation = base3_node_permutation(seed, level, prefix);
    scrambled_digits = scrambled_digits * 3 + kPermutations3[permutation][digit];
    prefix += digit * place;
    place *= 3;
  }
  return scrambled_digits;
}

uint64_t owen_unscramble_base3(uint64_t scrambled_digits, int levels, uint64_t seed) {
  uint64_t top_place = 1;
  for (int level = 1; level < levels; ++level) top_place *= 3;
  uint64_t prefix = 0;
  uint64_t place = 1;
  for (int level = 0; level < levels; ++level) {
    uint32_t scrambled = static_cast<uint32_t>((scrambled_digits / top_place) % 3);
    top_place /= 3;
    int permutation = base3_node_permutation(seed, level, prefix);
    prefix += kInversePermutations3[permutation][scrambled] * place;
    place *= 3;
  }
  return prefix;
}

double fraction_from_base2_digits(uint32_t top_bits, int levels, uint64_t random_bits) {
  if (levels <= 0) return bits_to_unit_double(random_bits);
  uint64_t digits = top_bits >> (32 - levels);
  uint64_t value53 = (digits << (53 - levels)) | (random_bits >> (11 + levels));
  return static_cast<double>(value53) * 0x1.0p-53;
}

}  // namespace penumbra
