#pragma once
// Low-discrepancy sequences and their randomization: the radical inverse (Halton bases 2 and 3),
// the first two Sobol' dimensions, and nested uniform (Owen) scrambling keyed by a stream.
//
// Owen scrambling (Owen 1995) permutes the base-b digits of a point: digit k is mapped by a random
// permutation chosen by (seed, k, digits 0..k-1 of the unscrambled point). It keeps every
// stratification property of the sequence (a (0,m,2)-net stays one) and makes each point
// uniform on [0,1). We draw each permutation from a hash of its tree node ("hash-based Owen
// scrambling", Burley 2020), so nothing is stored.
//
// For N points only the first L digits are permuted explicitly, L the fewest digits that tell the
// N points apart (b^L >= N: for the sequences here the first L digits of points 0..N-1 are all
// different). Below digit L every point has its own tree node, so Owen's permutations there are
// independent and the remaining digits are plain uniform random digits: the pattern fills them
// from the point's own random bits. The result is an exact Owen scramble of the N points.

#include <cstdint>

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

// Owen scrambling of the top `levels` (0..32) bits of a 0.32 fraction; lower bits pass through.
uint32_t owen_scramble_base2(uint32_t bits, int levels, uint64_t seed);
// Its inverse for the same levels and seed: owen_unscramble_base2(owen_scramble_base2(b)) == b.
uint32_t owen_unscramble_base2(uint32_t scrambled, int levels, uint64_t seed);

// Owen scrambling of the first `levels` (0..32) base-3 digits of the radical inverse of `index`:
// returns the scrambled digits as the integer sum_k d'_k 3^(levels-1-k), in [0, 3^levels).
uint64_t owen_scramble_base3(uint64_t index, int levels, uint64_t seed);
// Its inverse: given those scrambled digits, the index modulo 3^levels.
uint64_t owen_unscramble_base3(uint64_t scrambled_digits, int levels, uint64_t seed);

// A point of [0,1) whose first `levels` base-2 digits are `top_bits` (the top `levels` bits of
// a 0.32 fraction) and whose remaining digits are uniform random ones taken from `random_bits`.
// Exact: no rounding, so the point never leaves the elementary interval of its digits.
double fraction_from_base2_digits(uint32_t top_bits, int levels, uint64_t random_bits);

}  // namespace penumbra
