#pragma once
// The experiments of Ramamoorthi et al. 2012, Sec. 4 (Figs. 4, 6, 7), run on the visibility
// function alone (visibility_theory.h), as tables of data a command prints and charts
// (`penumbra reproduce`): each row is one (pattern, k, placement, N) with the measured expected
// squared error, the paper's (or our derived) closed form and their ratio.

#include <cstdint>
#include <string>
#include <vector>

#include "core/analysis/visibility_theory.h"
#include "core/image/chart.h"

namespace penumbra {

struct VisibilityReproductionOptions {
  int samples = 256;   // N (Fig. 7 uses 256)
  int trials = 20000;  // random discontinuity positions per row (Fig. 7 used 1000)
  uint64_t seed = 2012;
  int threads = 0;  // worker threads per experiment; 0: the hardware's count
};

struct VisibilityTable {
  std::string title;
  std::vector<VisibilityErrorResult> rows;
};

// Fig. 4: one discontinuity: samples at the strata's end-points 1/(3N^2), uniform 1/(12N^2),
// stratified and uniform jitter 1/(6N^2), the canonical Halton sequence near the end-point
// case, random 1/(6N).
VisibilityTable reproduce_one_discontinuity(const VisibilityReproductionOptions& options);
// Fig. 6: two discontinuities in different strata: uniform and uniform jitter 1/(6N^2),
// stratified 1/(3N^2); random (independent placement) 1/(6N).
VisibilityTable reproduce_two_discontinuities(const VisibilityReproductionOptions& options);
// Fig. 7a: k = 1..max_discontinuities in distinct strata, for uniform, uniform jitter,
// stratified, the canonical Halton sequence and the renderer's Halton.
VisibilityTable reproduce_discontinuity_count(const VisibilityReproductionOptions& options,
                                              int max_discontinuities = 7);
// Fig. 7b, the extreme case: many discontinuities in distinct strata (k up to 100, when N
// allows), then essentially random visibility (k = N, 4N, 16N independent discontinuities,
// several per stratum) where every pattern approaches stratified sampling.
VisibilityTable reproduce_extreme_case(const VisibilityReproductionOptions& options);
// Convergence: N = 4, 8, ..., options.samples (powers of two) for k discontinuities in distinct
// strata (random: independent): error ~ N^-2 for the stratified patterns, N^-1 for random.
VisibilityTable reproduce_convergence(const VisibilityReproductionOptions& options,
                                      int discontinuities = 2);

// Every table above, in order.
std::vector<VisibilityTable> reproduce_visibility_theory(
    const VisibilityReproductionOptions& options);

// A fixed-width text table: pattern, placement, k, N, trials, N^2 x measured (+- standard
// error), N^2 x predicted, ratio, formula.
std::string format_visibility_table(const VisibilityTable& table);

// N^2 x error against the number of discontinuities (Fig. 7): one measured series per pattern
// with 2-sigma error bars, and its prediction dashed in the same colour.
ChartSpec discontinuity_count_chart(const VisibilityTable& table);
// Error against N in log-log, per pattern, with the fitted slope in the legend.
ChartSpec convergence_chart(const VisibilityTable& table);

}  // namespace penumbra
