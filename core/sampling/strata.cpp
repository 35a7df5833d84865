#include "core/sampling/strata.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "core/sampling/counter_random.h"

namespace penumbra {

double point_in_stratum_nudged(uint64_t index, uint64_t count, double u) {
  double strata = static_cast<double>(count);
  double target = static_cast<double>(index);
  u = u >= 0.0 ? std::min(u, kOneMinusEpsilon) : 0.0;  // also NaN to 0
  double v = std::min((target + u) / strata, kOneMinusEpsilon);
  // Both the sum and the division round: a value within an ulp of a stratum boundary can land on
  // the wrong side of it. Step it back one ulp at a time (at most a few steps).
  while (v > 0.0 && std::floor(v * strata) > target) v = std::nextafter(v, 0.0);
  while (std::floor(v * strata) < target) v = std::nextafter(v, 1.0);
  return v;
}

uint64_t stratum_of(double v, uint64_t count) {
  if (count == 0) return 0;
  double scaled = std::floor(v * static_cast<double>(count));
  if (!(scaled > 0.0)) return 0;  // also NaN
  if (scaled >= static_cast<double>(count)) return count - 1;
  return static_cast<uint64_t>(scaled);
}

StrataGrid strata_grid(uint32_t n, double aspect) {
  StrataGrid grid;
  if (n == 0) return grid;
  if (!(aspect > 0.0)) aspect = 1.0;  // NaN, zero or negative: no shape information
  bool taller_than_wide = aspect < 1.0;
  double elongation = taller_than_wide ? 1.0 / aspect : aspect;  // >= 1, may be +inf

  uint32_t long_strata = n;
  if (elongation < static_cast<double>(n)) {
    double ideal = std::round(std::sqrt(static_cast<double>(n) * elongation));
    long_strata = static_cast<uint32_t>(std::clamp(ideal, 1.0, static_cast<double>(n)));
  }
  uint32_t short_strata = n / long_strata;

  grid.columns = long_strata;
  grid.rows = short_strata;
  grid.leftover_along_x = true;
  if (taller_than_wide) {
    std::swap(grid.columns, grid.rows);
    grid.leftover_along_x = false;
  }
  grid.leftover = n - long_strata * short_strata;
  return grid;
}

}  // namespace penumbra
