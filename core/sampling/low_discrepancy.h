#pragma once
// Low-discrepancy sequences and their randomization: the radical inverse (Halton bases 2 and 3),
// the first two Sobol' dimensions, and nested uniform (Owen) scrambling keyed by a stream.
//
// Owen scrambling (Owen 1995) permutes the base-b digits of a point: digit k is mapped by a random
// permutation chosen by (seed, k, digits 0..k-1 of the unscrambled point). It keeps every
// stratification property of the sequence (a (0,m,2)-net stays one) and makes each point
// uniform on [0,1). Each permutation comes from a hash of its tree node's id and the seed
// (hash-based Owen scrambling, as in Burley 2020, but with independent random digits per node
// rather than an approximating bit-mixing function), so nothing needs to be stored.
//
// For N points only the first L digits are permuted explicitly, L the fewest digits that tell the
// N points apart (b^L >= N: for the sequences here the first L digits of points 0..N-1 are all
// different). Below digit L every point has its own tree node, so Owen's permutations there are
// independent and the remaining digits are plain uniform random digits: the pattern fills them
// from the point's own random bits. The result is an exact Owen scramble of the N points.

#include <array>
#include <cstdint>
#include <span>

#include "core/sampling/pattern.h"

namespace penumbra {

// Reverses the 32 bits of a word: the base-2 radical inverse of `index` as a 0.32 fixed-point
// fraction (van der Corput), also Sobol' dimension 0.
constexpr uint32_t reverse_bits_32(uint32_t v) {
  v = ((v >> 1) & 0x55555555u) | ((v & 0x55555555u) << 1);
  v = ((v >> 2) & 0x33333333u) | ((v & 0x33333333u) << 2);
  v = ((v >> 4) & 0x0f0f0f0fu) | ((v & 0x0f0f0f0fu) << 4);
  v = ((v >> 8) & 0x00ff00ffu) | ((v & 0x00ff00ffu) << 8);
  return (v >> 16) | (v << 16);
}

// The unscrambled radical inverse of `index` in `base` >= 2 (reference; slow, exact digits).
double radical_inverse(uint32_t base, uint64_t index);

// Point `index` of Sobol' dimension 0 or 1 as a 0.32 fixed-point fraction (unscrambled).
// Dimension 0 is van der Corput. Dimension 1 uses primitive polynomial x + 1 (degree 1, m_1 = 1),
// so its direction numbers follow m_k = 2 m_{k-1} xor m_{k-1} (Bratley & Fox 1988, Eq. 2).
uint32_t sobol_bits(uint32_t index, int dimension);

// The fewest base-b digits that tell n points apart: ceil(log_b n) (0 for n <= 1).
int digits_to_separate(uint32_t base, uint64_t n);

// The Owen scrambling seed of one dimension of a stream.
uint64_t owen_seed(const StreamKey& key, uint32_t dimension);
class StreamRandom;
uint64_t owen_seed(const StreamRandom& stream, uint32_t dimension);  // the same, key hashed

// Owen scrambling in base 2 of the top `levels` (0..32) bits of a 0.32 fraction; lower bits pass
// through. Tree node (level k, prefix p = the k digits above) has id 2^k + p; its flip is bit
// (id mod 64) of the random word mix(seed ^ (id / 64) * golden), so the N points of a stream,
// which share their upper nodes, need only ceil(2^levels / 64) hashes: the scrambler keeps the
// words of the first 12 levels.
class OwenScramblerBase2 {
 public:
  OwenScramblerBase2(uint64_t seed, int levels, bool keep_words = true);
  uint32_t scramble(uint32_t bits) const {
    uint32_t scrambled = bits;
    for (int level = 0; level < levels_; ++level) {
      uint64_t prefix = level == 0 ? 0 : bits >> (32 - level);
      scrambled ^= flip((uint64_t{1} << level) | prefix) << (31 - level);
    }
    return scrambled;
  }
  // The inverse: restores the digits from the top, each flip depending only on those above it.
  uint32_t unscramble(uint32_t scrambled) const {
    uint32_t bits = scrambled;
    for (int level = 0; level < levels_; ++level) {
      uint64_t prefix = level == 0 ? 0 : bits >> (32 - level);
      bits ^= flip((uint64_t{1} << level) | prefix) << (31 - level);
    }
    return bits;
  }
  // Every scramble() of the first `levels` digits at once, for a whole stream of points: entry t
  // (t < 2^levels) is scramble(t << (32 - levels)) >> (32 - levels). Built level by level, about
  // 2 steps per entry where scramble() takes `levels` steps per point.
  void fill_table(std::span<uint32_t> table) const;

 private:
  static constexpr uint32_t kKeptWords = 64;  // node ids below 2^12
  uint64_t word(uint64_t index) const;
  uint32_t flip(uint64_t node) const {
    uint64_t index = node >> 6;
    uint64_t bits = index < kept_ ? words_[index] : word(index);
    return static_cast<uint32_t>(bits >> (node & 63)) & 1u;
  }
  uint64_t seed_;
  int levels_;
  uint32_t kept_ = 0;
  std::array<uint64_t, kKeptWords> words_;
};

// Owen scrambling in base 3 of the first `levels` (0..32) digits of the radical inverse of an
// index (digit k of the radical inverse is digit k of the index). Node (level k, prefix p = index
// mod 3^k) has id (3^k - 1)/2 + p and picks one of the 6 permutations of {0,1,2} from 32 random
// bits (half of the word mix(seed ^ salt ^ (id / 2) * golden); bias below 2^-29). Keeps the words
// of the first 6 levels.
class OwenScramblerBase3 {
 public:
  OwenScramblerBase3(uint64_t seed, int levels, bool keep_words = true);
  // The scrambled digits as the integer sum_k d'_k 3^(levels-1-k), in [0, 3^levels).
  uint64_t scramble(uint64_t index) const;
  // The inverse: the index modulo 3^levels whose scrambled digits these are.
  uint64_t unscramble(uint64_t scrambled_digits) const;
  // Every scramble() at once: entry i (i < 3^levels) is scramble(i). About 1.5 steps per entry.
  void fill_table(std::span<uint64_t> table) const;

 private:
  static constexpr uint32_t kKeptWords = 192;  // the (3^6 - 1)/2 = 364 nodes of 6 levels
  uint64_t word(uint64_t index) const;
  int permutation(uint64_t node) const {
    uint64_t index = node >> 1;
    uint64_t bits = index < kept_ ? words_[index] : word(index);
    uint64_t half = (node & 1) ? bits >> 32 : bits & 0xffffffffu;
    return static_cast<int>((half * 6) >> 32);
  }
  uint64_t seed_;
  int levels_;
  uint32_t kept_ = 0;
  std::array<uint64_t, kKeptWords> words_;
};

// One-off forms of the scramblers (no kept words), for tests and single points.
uint32_t owen_scramble_base2(uint32_t bits, int levels, uint64_t seed);
uint32_t owen_unscramble_base2(uint32_t scrambled, int levels, uint64_t seed);
uint64_t owen_scramble_base3(uint64_t index, int levels, uint64_t seed);
uint64_t owen_unscramble_base3(uint64_t scrambled_digits, int levels, uint64_t seed);

// A point of [0,1) whose first `levels` base-2 digits are `top_bits` (the top `levels` bits of
// a 0.32 fraction) and whose remaining digits are uniform random ones taken from `random_bits`.
// Exact: no rounding, so the point never leaves the elementary interval of its digits.
inline double fraction_from_base2_digits(uint32_t top_bits, int levels, uint64_t random_bits) {
  if (levels <= 0) return static_cast<double>(static_cast<int64_t>(random_bits >> 11)) * 0x1.0p-53;
  uint64_t digits = top_bits >> (32 - levels);
  uint64_t value53 = (digits << (53 - levels)) | (random_bits >> (11 + levels));
  return static_cast<double>(static_cast<int64_t>(value53)) * 0x1.0p-53;  // exact: < 2^53
}

}  // namespace penumbra
