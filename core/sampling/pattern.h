#pragma once
// Deterministic, counter-based sample patterns. Every random number is a pure function of
// (seed, pixel, pass, stream, sample, dimension): no state, no thread dependence, so any worker
// renders any tile bit-identically.
//
// A "stream" is one group of draws at one shading point: e.g. the pixel jitter, or the N samples
// of one method term for one light. A pattern generates the N samples of a stream together so it
// can stratify them (1D for line offsets, 2D for points on a light).

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "core/math/vec.h"

namespace penumbra {

enum class Pattern { Random, Stratified, Uniform, UniformJitter, Halton, Sobol, Cmj };

// "random", "stratified", ... as in SCENE_FORMAT.md; parse returns empty for unknown names.
std::string_view pattern_name(Pattern pattern);
std::optional<Pattern> parse_pattern(std::string_view name);

struct StreamKey {
  uint64_t seed = 0;
  uint64_t pixel = 0;   // y * width + x (or a probe point index)
  uint32_t pass = 0;    // progressive pass (trial index in the probe)
  uint32_t stream = 0;  // which group of draws at this shading point
};

// A uniform double in [0,1) for one (key, sample, dimension): the raw counter-based generator.
double random_uniform(const StreamKey& key, uint32_t sample, uint32_t dimension);
// A 64-bit hash of the key, sample and dimension (the generator's core).
uint64_t random_bits(const StreamKey& key, uint32_t sample, uint32_t dimension);

// The N = out.size() 1D samples of a stream in [0,1), stratified as the pattern promises.
void generate_1d(Pattern pattern, const StreamKey& key, std::span<double> out);

// The N = out.size() 2D samples of a stream in [0,1)^2. `aspect` (>= 1 means wider than tall:
// the light's long side over its short side, in the order of the two sample coordinates) shapes
// the strata grid: a thin quad gets N x 1 strata along its length, a square sqrt(N) x sqrt(N).
// The exact grid rule and what happens when N is not columns x rows: strata_grid() in strata.h;
// what each pattern promises: the top of pattern.cpp (tests/core/sampling/ checks each promise).
void generate_2d(Pattern pattern, const StreamKey& key, double aspect, std::span<Vec2> out);

// Shirley-Chiu concentric map from [0,1)^2 to the unit disk (preserves stratification).
Vec2 square_to_disk_concentric(const Vec2& u);

}  // namespace penumbra
