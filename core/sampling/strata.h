#pragma once
// Strata: the 1D interval arithmetic and the 2D grid shared by the stratified, uniform,
// uniform-jitter and cmj patterns.
//
// Convention (what the tests check): a value v lies in stratum j of `count` equal strata of
// [0,1) exactly when floor(v * count) == j, evaluated in double precision.

#include <cstdint>

namespace penumbra {

// The point at relative position u in [0,1) of stratum `index` of `count` (index < count):
// (index + u) / count, nudged by at most a few ulps so that floor(v * count) == index in double
// arithmetic. Always in [0,1).
inline double point_in_stratum(uint64_t index, uint64_t count, double u);

// The rare path of point_in_stratum: u outside [0,1), or a value rounded across a boundary.
double point_in_stratum_nudged(uint64_t index, uint64_t count, double u);

// The stratum of v among `count` equal strata (the convention above), clamped to [0, count).
uint64_t stratum_of(double v, uint64_t count);

// The strata grid of a 2D pattern of n samples on a light of the given aspect.
//
// Rule: aspect = long side / short side in the order of the two sample coordinates (> 1: wider
// than tall, < 1: taller than wide; NaN, 0 or negative count as 1). With a = max(aspect,
// 1/aspect): if a >= n the grid is n x 1 along the long side; otherwise the long side gets
// round(sqrt(n a)) strata (clamped to [1, n]) and the short side n / that (integer division).
//
// Leftovers: when columns * rows < n, the first columns * rows samples fill the grid and the
// remaining `leftover` (fewer than the long side's strata count) are stratified in 1D along the
// long side, one per 1/leftover-wide band, uniform across the short side.
//
// Guarantees: samples 0 .. columns*rows-1 put exactly one sample in every grid cell; samples
// columns*rows .. n-1 put exactly one in every band of the long side. Both groups are uniform
// over the unit square, so the estimator stays unbiased.
struct StrataGrid {
  uint32_t columns = 0;   // strata along the first coordinate (x)
  uint32_t rows = 0;      // strata along the second coordinate (y)
  uint32_t leftover = 0;  // samples beyond columns * rows
  bool leftover_along_x = true;
  uint32_t cells() const { return columns * rows; }
};
StrataGrid strata_grid(uint32_t n, double aspect);

inline double point_in_stratum(uint64_t index, uint64_t count, double u) {
  double strata = static_cast<double>(count);
  double target = static_cast<double>(index);
  double v = (target + u) / strata;
  double scaled = v * strata;
  // Almost always already inside (also false for NaN, which the slow path resolves).
  if (v < 1.0 && scaled >= target && scaled < target + 1.0) return v;
  return point_in_stratum_nudged(index, count, u);
}

}  // namespace penumbra
