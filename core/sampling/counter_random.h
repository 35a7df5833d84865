#pragma once
// The counter-based generator behind random_bits / random_uniform (pattern.h), exposed inline so
// a pattern that draws many numbers from one stream hashes the stream's key only once.
//
// Construction: the key's fields are absorbed one at a time, each followed by a full-avalanche
// 64-bit finalizer (the SplitMix64 output function, Steele, Lea & Flood 2014):
//   h = mix(seed ^ kSeedSalt)            key.seed
//   h = mix(h ^ pixel)                   key.pixel
//   h = mix(h ^ (pass << 32 | stream))   key.pass, key.stream
//   bits = mix(mix(h + (sample << 32 | dimension) * kGolden) ^ kOutputSalt)
// Every step is a bijection of h for fixed later inputs, so two keys that differ in exactly one
// field (seed, pixel, pass, stream, sample or dimension) always give different bits. Integer
// arithmetic only: identical bits on every machine and compiler.

#include <cstdint>

#include "core/sampling/pattern.h"

namespace penumbra {

// SplitMix64's finalizer: a bijection of 64-bit words in which every input bit flips each output
// bit with probability close to 1/2.
constexpr uint64_t mix_bits(uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

// 53 random bits as a double in [0,1): exact, never 1.
constexpr double bits_to_unit_double(uint64_t bits) {
  // Through int64: below 2^53 both conversions are exact, and the signed one is one instruction.
  return static_cast<double>(static_cast<int64_t>(bits >> 11)) * 0x1.0p-53;
}

// The largest double below 1.
inline constexpr double kOneMinusEpsilon = 0x1.fffffffffffffp-1;

// All the random numbers of one stream: the key is hashed once at construction.
class StreamRandom {
 public:
  constexpr explicit StreamRandom(const StreamKey& key) {
    uint64_t h = mix_bits(key.seed ^ kSeedSalt);
    h = mix_bits(h ^ key.pixel);
    h = mix_bits(h ^ ((static_cast<uint64_t>(key.pass) << 32) | key.stream));
    stream_hash_ = h;
  }

  constexpr uint64_t bits(uint32_t sample, uint32_t dimension) const {
    uint64_t counter = (static_cast<uint64_t>(sample) << 32) | dimension;
    return mix_bits(mix_bits(stream_hash_ + counter * kGolden) ^ kOutputSalt);
  }
  constexpr double uniform(uint32_t sample, uint32_t dimension) const {
    return bits_to_unit_double(bits(sample, dimension));
  }

 private:
  static constexpr uint64_t kSeedSalt = 0x7a3c9e15d2b84f61ull;
  static constexpr uint64_t kOutputSalt = 0x3f84d5b5b5470917ull;
  static constexpr uint64_t kGolden = 0x9e3779b97f4a7c15ull;  // 2^64 / golden ratio, odd
  uint64_t stream_hash_ = 0;
};

// Sample indices at the top of the range are reserved for per-stream draws, so they never
// collide with a per-sample draw (patterns take at most 2^32 - 16 samples per stream).
inline constexpr uint32_t kStreamDrawSample = 0xffffffffu;         // jitter offset, Owen seeds
inline constexpr uint32_t kColumnPermutationSample = 0xfffffffeu;  // cmj shuffles
inline constexpr uint32_t kRowPermutationSample = 0xfffffffdu;
inline constexpr uint32_t kCellOrderSample = 0xfffffffcu;  // which stratum each sample visits
inline constexpr uint32_t kBandOrderSample = 0xfffffffbu;

}  // namespace penumbra
