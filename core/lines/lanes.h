#pragma once
// Short SIMD vectors for the line query, written with GCC's vector extensions so that one source
// serves every instruction set: the compiler emits SSE2 (two halves for the 8-float and 4-double
// types) in ordinary functions and AVX in functions compiled for AVX (line_query.cpp compiles
// its traversal twice and picks one at run time). Each lane does the same IEEE operation in the
// same order either way (the build has -ffp-contract=off: no fused multiply-add), so both builds
// give the same bits.
//
// Comparisons give integer lanes of 0 or -1 (all bits set); `movemask` turns them into bits.
// Ordered comparisons are false for NaN lanes (empty BVH slots hold NaN centres).

#include <immintrin.h>

#include <cstdint>

namespace penumbra::lanes {

typedef float F4 __attribute__((vector_size(16)));
typedef float F8 __attribute__((vector_size(32)));
typedef int32_t I8 __attribute__((vector_size(32)));
typedef double D2 __attribute__((vector_size(16)));
typedef double D4 __attribute__((vector_size(32)));

inline F8 load(const float (&values)[8]) {
  F8 v;
  __builtin_memcpy(&v, values, sizeof v);
  return v;
}
inline void store(float (&values)[8], const F8& v) {
  __builtin_memcpy(values, &v, sizeof v);
}
// Four floats widened to doubles (exact).
inline D4 widen(const float (&values)[4]) {
  F4 v;
  __builtin_memcpy(&v, values, sizeof v);
  return __builtin_convertvector(v, D4);
}

// |v|: the sign bit cleared.
inline F8 absolute(const F8& v) {
  return reinterpret_cast<F8>(reinterpret_cast<I8>(v) & 0x7fffffff);
}
// The larger lane, `b` when they are equal or either is NaN (as SSE's maxps).
inline F8 maximum(const F8& a, const F8& b) {
  return a > b ? a : b;
}

// Bit i set when lane i of `mask` is set. With SSE two 4-lane halves; with AVX one instruction
// (the AVX policy must be inlined into a function compiled for AVX).
struct SseMask {
  static unsigned of(const I8& mask) {
    __m128 lower, upper;
    __builtin_memcpy(&lower, &mask, sizeof lower);
    __builtin_memcpy(&upper, reinterpret_cast<const char*>(&mask) + sizeof lower, sizeof upper);
    return static_cast<unsigned>(_mm_movemask_ps(lower) | (_mm_movemask_ps(upper) << 4));
  }
};
#if defined(__x86_64__) || defined(__i386__)
struct AvxMask {
  __attribute__((target("avx"))) static unsigned of(const I8& mask) {
    __m256 lanes;
    __builtin_memcpy(&lanes, &mask, sizeof lanes);
    return static_cast<unsigned>(_mm256_movemask_ps(lanes));
  }
};
#endif

}  // namespace penumbra::lanes
