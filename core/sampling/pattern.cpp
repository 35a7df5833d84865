// The sample patterns of pattern.h. What each promises (tests/core/sampling/ checks it):
//
// random          independent uniform points.
// stratified      one independent uniform point in each stratum: 1D, N equal strata; 2D, the
//                 strata_grid() cells plus its 1D-stratified leftovers (strata.h).
// uniform         the centre of each of those strata: no randomness at all.
// uniform-jitter  the uniform pattern shifted by one random offset per stream, the same offset in
//                 every stratum (Ramamoorthi et al. 2012, Sec. 4.2.2): 1D (k + xi) / N for the
//                 N strata k.
// halton          radical inverses in bases 2 (x) and 3 (y) of indices 0..N-1, Owen scrambled
//                 per stream (low_discrepancy.h). The first 2^a 3^b points put one point in each
//                 box [i/2^a, (i+1)/2^a) x [j/3^b, (j+1)/3^b). 1D: base 2.
// sobol           Sobol' dimensions 0 and 1 of indices 0..N-1, Owen scrambled per stream. For
//                 N = 2^k the points form a (0,k,2)-net: one point in each elementary interval
//                 of area 1/N. 1D: dimension 0 (the same construction as halton's 1D).
// cmj             correlated multi-jittered sampling (Kensler 2013) on the strata_grid() cells:
//                 one point per cell, and the cell points also fill each of the cells() thin
//                 strata of x and of y exactly once (n-rooks). Leftovers as stratified. 1D:
//                 multi-jittering has no second axis to correlate, so it is stratified.
//
// Halton and Sobol' ignore `aspect`: they are sequences, not grids.
//
// Sample order. In stratified, uniform-jitter and cmj, sample i visits a stratum chosen by a
// random permutation per stream (cells and leftover bands separately: samples 0..cells()-1 are
// still the grid's, the rest the bands'). So every sample index on its own is uniform over the
// square, and sample i of one stream is independent of sample i of another: an estimator that
// pairs them (pixel jitter i with light sample i) stays unbiased. Halton and Sobol' points are
// each uniform already (Owen scrambling). The uniform pattern keeps its fixed order (no
// randomness at all), so it pairs deterministically with other streams.

#include "core/sampling/pattern.h"

#include <algorithm>
#include <array>
#include <vector>

#include "core/sampling/counter_random.h"
#include "core/sampling/low_discrepancy.h"
#include "core/sampling/strata.h"

namespace penumbra {

namespace {

constexpr std::array<Pattern, 7> kAllPatterns = {
    Pattern::Random, Pattern::Stratified, Pattern::Uniform, Pattern::UniformJitter,
    Pattern::Halton, Pattern::Sobol,      Pattern::Cmj};

// A uniform random integer in [0, bound) from 32 random bits (multiply-shift; the bias is at most
// bound / 2^32, far below anything a pattern of a few thousand samples could show).
inline uint32_t bounded_index(uint64_t bits, uint32_t bound) {
  return static_cast<uint32_t>(((bits >> 32) * bound) >> 32);
}

// An array whose storage is inline for small sizes, so small patterns never allocate.
template <typename T>
class SmallBuffer {
 public:
  explicit SmallBuffer(size_t size) : size_(size) {
    if (size > kInline) heap_.resize(size);
  }
  T* data() { return size_ > kInline ? heap_.data() : inline_.data(); }
  std::span<T> span() { return {data(), size_}; }
  T operator[](size_t i) const { return size_ > kInline ? heap_[i] : inline_[i]; }

 private:
  static constexpr size_t kInline = 128;
  size_t size_;
  std::array<T, kInline> inline_;  // filled by the owner
  std::vector<T> heap_;
};

// A uniformly random permutation of [0, size) (Fisher & Yates), drawn from the stream's
// (sample, j) numbers, 32 bits per swap; or the identity when not `shuffled`.
class Permutation {
 public:
  Permutation(const StreamRandom& rng, uint32_t sample, uint32_t size, bool shuffled = true)
      : shuffled_(shuffled), values_(shuffled ? size : 0) {
    if (!shuffled) return;
    uint32_t* p = values_.data();
    for (uint32_t i = 0; i < size; ++i) p[i] = i;
    uint64_t word = 0;
    for (uint32_t i = size; i > 1; --i) {
      bool high_half = ((size - i) & 1u) == 0;
      if (high_half) word = rng.bits(sample, i);
      uint32_t j = bounded_index(high_half ? word : word << 32, i);
      std::swap(p[i - 1], p[j]);
    }
  }
  uint32_t operator[](uint32_t i) const { return shuffled_ ? values_[i] : i; }

 private:
  bool shuffled_;
  SmallBuffer<uint32_t> values_;
};

// Above this many digits the scrambled-digit tables (2^levels or 3^levels entries) would cost
// more memory than they save time: scramble point by point instead.
constexpr int kMaxTableLevelsBase2 = 16;
constexpr int kMaxTableLevelsBase3 = 10;

// The scrambled first `levels` base-2 digits of the stream's points: a table when it is small,
// else scramble() per point. With 0 levels there is nothing to scramble (and no seed to draw).
class ScrambledBase2Digits {
 public:
  ScrambledBase2Digits(const StreamRandom& rng, uint32_t dimension, int levels)
      : scrambler_(levels > 0 ? owen_seed(rng, dimension) : 0, levels),
        levels_(levels),
        table_(levels <= kMaxTableLevelsBase2 ? size_t{1} << levels : 0) {
    if (levels > 0 && levels <= kMaxTableLevelsBase2) scrambler_.fill_table(table_.span());
  }
  // The scrambled digits of the point whose unscrambled 0.32 fraction is `bits` (all digits
  // below `levels` zero), as a 0.32 fraction.
  uint32_t scramble(uint32_t bits) const {
    if (levels_ == 0) return 0;
    if (levels_ > kMaxTableLevelsBase2) return scrambler_.scramble(bits);
    return table_[bits >> (32 - levels_)] << (32 - levels_);
  }

 private:
  OwenScramblerBase2 scrambler_;
  int levels_;
  SmallBuffer<uint32_t> table_;
};

class ScrambledBase3Digits {
 public:
  ScrambledBase3Digits(const StreamRandom& rng, uint32_t dimension, int levels)
      : scrambler_(levels > 0 ? owen_seed(rng, dimension) : 0, levels),
        levels_(levels),
        table_(levels <= kMaxTableLevelsBase3 ? power_of_three(levels) : 0) {
    if (levels > 0 && levels <= kMaxTableLevelsBase3) scrambler_.fill_table(table_.span());
  }
  uint64_t scramble(uint32_t index) const {
    if (levels_ == 0) return 0;
    return levels_ <= kMaxTableLevelsBase3 ? table_[index] : scrambler_.scramble(index);
  }
  static uint64_t power_of_three(int exponent) {
    uint64_t p = 1;
    for (int i = 0; i < exponent; ++i) p *= 3;
    return p;
  }

 private:
  OwenScramblerBase3 scrambler_;
  int levels_;
  SmallBuffer<uint64_t> table_;
};

// Places the samples of a strata-grid pattern: `position_in_stratum(i)` gives sample i's relative
// position (each coordinate in [0,1)) inside its cell or leftover band; `shuffled` picks a random
// sample order (see "Sample order" above) over the fixed row-major one.
template <typename PositionInStratum>
void fill_strata_grid(const StreamRandom& rng, bool shuffled, const StrataGrid& grid,
                      std::span<Vec2> out, PositionInStratum position_in_stratum) {
  uint32_t cells = grid.cells();
  Permutation cell_order(rng, kCellOrderSample, cells, shuffled);
  for (uint32_t i = 0; i < cells; ++i) {
    Vec2 u = position_in_stratum(i);
    uint32_t cell = cell_order[i];
    out[i] = {point_in_stratum(cell % grid.columns, grid.columns, u.x),
              point_in_stratum(cell / grid.columns, grid.rows, u.y)};
  }
  // Leftovers: 1D strata along the long side, free across the short side.
  Permutation band_order(rng, kBandOrderSample, grid.leftover, shuffled);
  for (uint32_t j = 0; j < grid.leftover; ++j) {
    uint32_t i = cells + j;
    uint32_t band = band_order[j];
    Vec2 u = position_in_stratum(i);
    if (grid.leftover_along_x) {
      out[i] = {point_in_stratum(band, grid.leftover, u.x), u.y};
    } else {
      out[i] = {u.x, point_in_stratum(band, grid.leftover, u.y)};
    }
  }
}

// Kensler 2013, Sec. 3 (correlated multi-jittering) on an m x n grid: sample s sits in cell
// c = (s' % m, s' / m), s' the shuffled order of s (Kensler also permutes s); its x lies in thin
// stratum col * n + P_x[row] of the m n strata of [0,1), its y in thin stratum row * m + P_y[col],
// where P_x shuffles [0,n) and P_y shuffles [0,m) once per stream (the "correlated" part: every row
// shares one shuffle, every column one).
void correlated_multi_jittered(const StreamRandom& rng, const StrataGrid& grid,
                               std::span<Vec2> out) {
  uint32_t m = grid.columns;
  uint32_t n = grid.rows;
  uint32_t cells = grid.cells();
  Permutation x_substratum_of_row(rng, kRowPermutationSample, n);
  Permutation y_substratum_of_column(rng, kColumnPermutationSample, m);
  Permutation cell_order(rng, kCellOrderSample, cells);
  for (uint32_t s = 0; s < cells; ++s) {
    uint32_t column = cell_order[s] % m;
    uint32_t row = cell_order[s] / m;
    out[s] = {point_in_stratum(column * n + x_substratum_of_row[row], cells, rng.uniform(s, 0)),
              point_in_stratum(row * m + y_substratum_of_column[column], cells, rng.uniform(s, 1))};
  }
  fill_strata_grid(rng, true, StrataGrid{0, 0, grid.leftover, grid.leftover_along_x},
                   out.subspan(cells), [&](uint32_t band) {
                     uint32_t s = cells + band;
                     return Vec2(rng.uniform(s, 0), rng.uniform(s, 1));
                   });
}

// Owen-scrambled base-2 coordinate of point `index`: `scrambled_digits` holds its first `levels`
// scrambled digits (a 0.32 fraction); the digits below are the point's own random bits
// (low_discrepancy.h).
inline double scrambled_base2(const StreamRandom& rng, uint32_t index, uint32_t dimension,
                              uint32_t scrambled_digits, int levels) {
  return fraction_from_base2_digits(scrambled_digits, levels, rng.bits(index, dimension));
}

}  // namespace

std::string_view pattern_name(Pattern pattern) {
  switch (pattern) {
    case Pattern::Random:
      return "random";
    case Pattern::Stratified:
      return "stratified";
    case Pattern::Uniform:
      return "uniform";
    case Pattern::UniformJitter:
      return "uniform-jitter";
    case Pattern::Halton:
      return "halton";
    case Pattern::Sobol:
      return "sobol";
    case Pattern::Cmj:
      return "cmj";
  }
  return "unknown";
}

std::optional<Pattern> parse_pattern(std::string_view name) {
  for (Pattern pattern : kAllPatterns) {
    if (pattern_name(pattern) == name) return pattern;
  }
  return std::nullopt;
}

void generate_1d(Pattern pattern, const StreamKey& key, std::span<double> out) {
  uint32_t n = static_cast<uint32_t>(out.size());
  StreamRandom rng(key);
  switch (pattern) {
    case Pattern::Random:
      for (uint32_t i = 0; i < n; ++i) out[i] = rng.uniform(i, 0);
      return;
    case Pattern::Stratified:
    case Pattern::Cmj: {
      Permutation order(rng, kCellOrderSample, n);
      for (uint32_t i = 0; i < n; ++i) out[i] = point_in_stratum(order[i], n, rng.uniform(i, 0));
      return;
    }
    case Pattern::Uniform:
      for (uint32_t i = 0; i < n; ++i) out[i] = point_in_stratum(i, n, 0.5);
      return;
    case Pattern::UniformJitter: {
      double offset = rng.uniform(kStreamDrawSample, 0);
      Permutation order(rng, kCellOrderSample, n);
      for (uint32_t i = 0; i < n; ++i) out[i] = point_in_stratum(order[i], n, offset);
      return;
    }
    case Pattern::Halton:
    case Pattern::Sobol: {
      int levels = digits_to_separate(2, n);
      ScrambledBase2Digits digits(rng, 0, levels);
      for (uint32_t i = 0; i < n; ++i) {
        out[i] = scrambled_base2(rng, i, 0, digits.scramble(reverse_bits_32(i)), levels);
      }
      return;
    }
  }
}

void generate_2d(Pattern pattern, const StreamKey& key, double aspect, std::span<Vec2> out) {
  uint32_t n = static_cast<uint32_t>(out.size());
  if (n == 0) return;
  StreamRandom rng(key);
  switch (pattern) {
    case Pattern::Random:
      for (uint32_t i = 0; i < n; ++i) out[i] = {rng.uniform(i, 0), rng.uniform(i, 1)};
      return;
    case Pattern::Stratified:
      fill_strata_grid(rng, true, strata_grid(n, aspect), out,
                       [&](uint32_t i) { return Vec2(rng.uniform(i, 0), rng.uniform(i, 1)); });
      return;
    case Pattern::Uniform:
      fill_strata_grid(rng, false, strata_grid(n, aspect), out,
                       [](uint32_t) { return Vec2(0.5, 0.5); });
      return;
    case Pattern::UniformJitter: {
      Vec2 offset(rng.uniform(kStreamDrawSample, 0), rng.uniform(kStreamDrawSample, 1));
      fill_strata_grid(rng, true, strata_grid(n, aspect), out, [&](uint32_t) { return offset; });
      return;
    }
    case Pattern::Halton: {
      int levels2 = digits_to_separate(2, n);
      int levels3 = digits_to_separate(3, n);
      uint64_t strata3 = ScrambledBase3Digits::power_of_three(levels3);
      ScrambledBase2Digits digits_x(rng, 0, levels2);
      ScrambledBase3Digits digits_y(rng, 1, levels3);
      for (uint32_t i = 0; i < n; ++i) {
        double x = scrambled_base2(rng, i, 0, digits_x.scramble(reverse_bits_32(i)), levels2);
        // Base 3: the scrambled digits pick one of 3^levels3 strata, the rest is uniform in it.
        uint64_t stratum = digits_y.scramble(i);
        out[i] = {x, point_in_stratum(stratum, strata3, rng.uniform(i, 1))};
      }
      return;
    }
    case Pattern::Sobol: {
      int levels = digits_to_separate(2, n);
      ScrambledBase2Digits digits_x(rng, 0, levels);
      ScrambledBase2Digits digits_y(rng, 1, levels);
      for (uint32_t i = 0; i < n; ++i) {
        out[i] = {scrambled_base2(rng, i, 0, digits_x.scramble(reverse_bits_32(i)), levels),
                  scrambled_base2(rng, i, 1, digits_y.scramble(sobol_bits(i, 1)), levels)};
      }
      return;
    }
    case Pattern::Cmj:
      correlated_multi_jittered(rng, strata_grid(n, aspect), out);
      return;
  }
}

}  // namespace penumbra
