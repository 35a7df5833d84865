#pragma once
// The visibility-sampling theory of Ramamoorthi et al. 2012 ("A Theory of Monte Carlo Visibility
// Sampling", Sec. 4) on its own terms: a binary visibility function over a linear light,
// parametrized by y in [0,1), with k discontinuities; its integral S (the fractional visibility,
// Eq. 4) estimated from N samples of a pattern (Eq. 6, 14); and the expected squared error
// <(S - S_bar)^2> over random discontinuity positions, measured by Monte Carlo over many trials
// and compared with the paper's closed forms (Figs. 4, 6, 7).
//
// Everything is deterministic: trial t draws its discontinuities and its samples from counter-
// based streams keyed by (seed, pixel = t), so a result is the same on every machine.

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/sampling/pattern.h"

namespace penumbra {

// The sample patterns of the experiments: the renderer's patterns (core/sampling/pattern.h), and
// two deterministic ones of the paper the renderer does not use (they are the same for every
// pixel): the canonical, unrandomized Halton sequence (radical inverse base 2 of 1..N, "[1/2,
// 1/4, 3/4, 1/8]", Sec. 4.1) and samples at the end-points of the strata, i/N (Fig. 4's worst
// placement).
enum class VisibilityPattern {
  Uniform,
  UniformJitter,
  Stratified,
  Halton,
  Random,
  CanonicalHalton,
  StratumEnds
};

std::string_view visibility_pattern_name(VisibilityPattern pattern);
// The renderer's pattern behind a visibility pattern; empty for CanonicalHalton and StratumEnds.
std::optional<Pattern> renderer_pattern(VisibilityPattern pattern);

// How the k discontinuities of a trial are placed.
enum class DiscontinuityPlacement {
  // Each in a different one of the N strata [i/N, (i+1)/N), uniformly: the assumption of the
  // paper's analysis (Sec. 4.2.1: "the discontinuities lie in different strata").
  DistinctStrata,
  // Independent and uniform over [0,1): several may share a stratum ("essentially random
  // visibility", Fig. 7b and Sec. 7, Fig. 21).
  Independent,
};

std::string_view placement_name(DiscontinuityPlacement placement);

// A binary visibility function over [0,1): `visible_at_start` on [0, d_0), toggling at each
// discontinuity d_i (sorted, in [0,1)).
struct VisibilityFunction {
  bool visible_at_start = false;
  std::vector<double> discontinuities;

  bool visible(double y) const;
  // S = the measure of the visible set (Eq. 5, 13).
  double integral() const;
};

// The visibility function of one trial: k discontinuities placed as asked over N strata, drawn
// from the stream `key` (the start state is random too; the error statistics do not depend on
// it). Throws std::invalid_argument for k < 0, N < 1, or DistinctStrata with k > N.
VisibilityFunction random_visibility_function(int discontinuities, DiscontinuityPlacement placement,
                                              int strata, const StreamKey& key);

// The N = out.size() samples of a pattern in [0,1) for one trial.
void generate_visibility_samples(VisibilityPattern pattern, const StreamKey& key,
                                 std::span<double> out);

// S_bar = (1/N) sum V(y_k) (Eq. 6 and 14). Zero for no samples.
double estimate_visibility_integral(const VisibilityFunction& visibility,
                                    std::span<const double> samples);

// A closed form of the expected squared error, with how it was obtained.
struct PredictedError {
  double value = 0;     // <(S - S_bar)^2>
  std::string formula;  // e.g. "k/(12 N^2)"
  std::string source;   // e.g. "Fig. 4, Eq. 11"
};

// The expected squared error of a pattern for k discontinuities placed as given over N strata,
// when a closed form exists (see the .cpp for each derivation):
//   DistinctStrata: uniform k/(12N^2), stratified k/(6N^2) (Figs. 4, 6), uniform jitter
//     (k + (k mod 2))/(12N^2) (Fig. 6 and Sec. 4.2.2: each box 1/6, an odd one +1/12), stratum
//     end-points (k/12 + [k odd]/4)/N^2 (1/(3N^2) for k = 1, Fig. 4), the canonical Halton
//     sequence at N = 2^m, and this renderer's Owen-scrambled Halton at N = 2^m (which is
//     jittered stratified sampling there, so as stratified).
//   Independent: random E[S(1-S)]/N (the variance of the step, 1/N); stratified (and the
//     renderer's Halton at N = 2^m) as a sum over strata of E[f(1-f)]/N^2 (f a stratum's visible
//     fraction); and, for k = 1 (one discontinuity is always alone in its stratum), the
//     DistinctStrata forms.
//   Random with DistinctStrata has none (use Independent; its error does not see strata).
std::optional<PredictedError> predicted_squared_error(VisibilityPattern pattern,
                                                      int discontinuities,
                                                      DiscontinuityPlacement placement,
                                                      int samples);

struct VisibilityExperiment {
  VisibilityPattern pattern = VisibilityPattern::Stratified;
  int discontinuities = 1;
  DiscontinuityPlacement placement = DiscontinuityPlacement::DistinctStrata;
  int samples = 16;    // N
  int trials = 10000;  // random discontinuity positions (and pattern draws)
  uint64_t seed = 1;
  // Worker threads over the trials (0: the hardware's count). The result does not depend on it:
  // each trial's error is stored and they are summed in trial order.
  int threads = 0;
};

struct VisibilityErrorResult {
  VisibilityExperiment experiment;
  double mean_squared_error = 0;  // measured <(S - S_bar)^2> over the trials
  double standard_error = 0;      // of that mean (sample standard deviation / sqrt(trials))
  std::optional<PredictedError> predicted;
  std::optional<double> ratio;  // measured / predicted, when there is a prediction

  // N^2 <(S - S_bar)^2>, the normalization of Fig. 7.
  double normalized_error() const {
    return mean_squared_error * double(experiment.samples) * double(experiment.samples);
  }
};

// Runs the trials of one experiment. Throws std::invalid_argument for N < 1, trials < 2, or a
// placement that cannot hold k discontinuities.
VisibilityErrorResult run_visibility_experiment(const VisibilityExperiment& experiment);

}  // namespace penumbra
