// Ramamoorthi et al. 2012, Sec. 4: visibility over a linear light, its estimate, and the expected
// squared error of sample patterns, measured and predicted.

#include "core/analysis/visibility_theory.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <thread>
#include <unordered_set>

namespace penumbra {

namespace {

// Streams of one trial: the pattern's samples and the discontinuity positions.
constexpr uint32_t kSampleStream = 0;
constexpr uint32_t kDiscontinuityStream = 1;

// Dimensions of the discontinuity stream.
constexpr uint32_t kStratumChoiceDimension = 0;
constexpr uint32_t kPositionDimension = 1;
constexpr uint32_t kStartStateDimension = 2;

bool is_power_of_two(int n) {
  return n > 0 && (n & (n - 1)) == 0;
}

// Base-2 radical inverse (van der Corput) of a non-negative index.
double radical_inverse_base2(uint32_t index) {
  double inverse = 0, digit_weight = 0.5;
  for (; index > 0; index >>= 1, digit_weight *= 0.5)
    if (index & 1u) inverse += digit_weight;
  return inverse;
}

// E[f(1-f)], the variance of the visibility of one uniform sample of an interval averaged over
// the interval's visible fraction f, when j independent uniform discontinuities cut it: the j+1
// spacings are Dirichlet(1,...,1), f is the sum of m = floor((j+1)/2) of them (the visible ones;
// m(j+1-m) is the same whichever state the interval starts in), so f is Beta(m, j+1-m) and
// E[f(1-f)] = m(j+1-m) / ((j+1)(j+2)).
double expected_visibility_sample_variance(int j) {
  double m = double((j + 1) / 2);
  return m * (double(j + 1) - m) / (double(j + 1) * double(j + 2));
}

// The probability of j successes among k trials of probability p.
double binomial_probability(int k, int j, double p) {
  if (p >= 1) return j == k ? 1.0 : 0.0;
  if (p <= 0) return j == 0 ? 1.0 : 0.0;
  double log_choose = std::lgamma(k + 1.0) - std::lgamma(j + 1.0) - std::lgamma(k - j + 1.0);
  return std::exp(log_choose + j * std::log(p) + (k - j) * std::log1p(-p));
}

void check_counts(int discontinuities, DiscontinuityPlacement placement, int strata) {
  if (strata < 1)
    throw std::invalid_argument("visibility experiment: need at least 1 sample/stratum, got " +
                                std::to_string(strata));
  if (discontinuities < 0)
    throw std::invalid_argument("visibility experiment: negative discontinuity count " +
                                std::to_string(discontinuities));
  if (placement == DiscontinuityPlacement::DistinctStrata && discontinuities > strata)
    throw std::invalid_argument("visibility experiment: " + std::to_string(discontinuities) +
                                " discontinuities cannot lie in distinct strata of " +
                                std::to_string(strata));
}

}  // namespace

std::string_view visibility_pattern_name(VisibilityPattern pattern) {
  switch (pattern) {
    case VisibilityPattern::Uniform:
      return "uniform";
    case VisibilityPattern::UniformJitter:
      return "uniform-jitter";
    case VisibilityPattern::Stratified:
      return "stratified";
    case VisibilityPattern::Halton:
      return "halton";
    case VisibilityPattern::Random:
      return "random";
    case VisibilityPattern::CanonicalHalton:
      return "halton-canonical";
    case VisibilityPattern::StratumEnds:
      return "stratum-ends";
  }
  return "unknown";
}

std::optional<Pattern> renderer_pattern(VisibilityPattern pattern) {
  switch (pattern) {
    case VisibilityPattern::Uniform:
      return Pattern::Uniform;
    case VisibilityPattern::UniformJitter:
      return Pattern::UniformJitter;
    case VisibilityPattern::Stratified:
      return Pattern::Stratified;
    case VisibilityPattern::Halton:
      return Pattern::Halton;
    case VisibilityPattern::Random:
      return Pattern::Random;
    case VisibilityPattern::CanonicalHalton:
    case VisibilityPattern::StratumEnds:
      return std::nullopt;
  }
  return std::nullopt;
}

std::string_view placement_name(DiscontinuityPlacement placement) {
  switch (placement) {
    case DiscontinuityPlacement::DistinctStrata:
      return "distinct-strata";
    case DiscontinuityPlacement::Independent:
      return "independent";
  }
  return "unknown";
}

bool VisibilityFunction::visible(double y) const {
  auto toggles =
      std::upper_bound(discontinuities.begin(), discontinuities.end(), y) - discontinuities.begin();
  return visible_at_start != (toggles % 2 == 1);
}

double VisibilityFunction::integral() const {
  double visible_measure = 0, run_start = 0;
  bool state = visible_at_start;
  for (double d : discontinuities) {
    double end = std::clamp(d, 0.0, 1.0);
    if (state) visible_measure += end - run_start;
    run_start = end;
    state = !state;
  }
  if (state) visible_measure += 1.0 - run_start;
  return visible_measure;
}

VisibilityFunction random_visibility_function(int discontinuities, DiscontinuityPlacement placement,
                                              int strata, const StreamKey& key) {
  check_counts(discontinuities, placement, strata);
  VisibilityFunction visibility;
  visibility.visible_at_start = random_uniform(key, 0, kStartStateDimension) < 0.5;
  visibility.discontinuities.reserve(discontinuities);

  if (placement == DiscontinuityPlacement::Independent) {
    for (int i = 0; i < discontinuities; ++i)
      visibility.discontinuities.push_back(random_uniform(key, uint32_t(i), kPositionDimension));
  } else {
    // Choose k distinct strata uniformly (Floyd's sampling of a k-subset of {0..N-1}), then a
    // uniform position inside each.
    std::unordered_set<int> chosen;
    std::vector<int> strata_chosen;
    for (int j = strata - discontinuities, draw = 0; j < strata; ++j, ++draw) {
      int t =
          std::min(int(random_uniform(key, uint32_t(draw), kStratumChoiceDimension) * (j + 1)), j);
      int stratum = chosen.count(t) ? j : t;
      chosen.insert(stratum);
      strata_chosen.push_back(stratum);
    }
    for (size_t i = 0; i < strata_chosen.size(); ++i) {
      double u = random_uniform(key, uint32_t(i), kPositionDimension);
      double position = (strata_chosen[i] + u) / strata;
      // Rounding may land (s + u)/N on the next stratum's edge; keep it inside its own.
      double stratum_end = double(strata_chosen[i] + 1) / strata;
      visibility.discontinuities.push_back(std::min(position, std::nextafter(stratum_end, 0.0)));
    }
  }
  std::sort(visibility.discontinuities.begin(), visibility.discontinuities.end());
  return visibility;
}

void generate_visibility_samples(VisibilityPattern pattern, const StreamKey& key,
                                 std::span<double> out) {
  if (auto renderer = renderer_pattern(pattern)) {
    generate_1d(*renderer, key, out);
    return;
  }
  // Deterministic, the same for every trial: the paper's Halton points h(1), ..., h(N), or the
  // strata's left end-points i/N.
  for (size_t i = 0; i < out.size(); ++i)
    out[i] = pattern == VisibilityPattern::StratumEnds ? double(i) / double(out.size())
                                                       : radical_inverse_base2(uint32_t(i + 1));
}

double estimate_visibility_integral(const VisibilityFunction& visibility,
                                    std::span<const double> samples) {
  if (samples.empty()) return 0;
  size_t visible_count = 0;
  for (double y : samples) visible_count += visibility.visible(y) ? 1 : 0;
  return double(visible_count) / double(samples.size());
}

std::optional<PredictedError> predicted_squared_error(VisibilityPattern pattern,
                                                      int discontinuities,
                                                      DiscontinuityPlacement placement,
                                                      int samples) {
  check_counts(discontinuities, placement, samples);
  const int k = discontinuities;
  const double n = samples, n2 = n * n;
  const bool odd = k % 2 == 1;
  // One discontinuity is always alone in its stratum: both placements are the same.
  if (k <= 1) placement = DiscontinuityPlacement::DistinctStrata;

  // Random sampling ignores strata: each sample sees the visible set with probability S, so
  // <(S - S_bar)^2> = E[S(1-S)]/N, "1/N times the variance of the step"; for k independent
  // uniform discontinuities S is Beta(m, k+1-m) (see expected_visibility_sample_variance).
  if (pattern == VisibilityPattern::Random) {
    if (placement != DiscontinuityPlacement::Independent && k > 1) return std::nullopt;
    return PredictedError{expected_visibility_sample_variance(k) / n,
                          "m(k+1-m)/((k+1)(k+2) N), m=floor((k+1)/2)",
                          "variance of a Bernoulli(S) sample / N"};
  }

  // This renderer's Halton in 1D is an Owen-scrambled van der Corput sequence: at N = 2^m its
  // points are one per stratum [i/N, (i+1)/N), each uniform in its stratum and independent of
  // the others (core/sampling/low_discrepancy.h): jittered stratified sampling.
  if (pattern == VisibilityPattern::Halton) {
    if (!is_power_of_two(samples)) return std::nullopt;
    auto stratified =
        predicted_squared_error(VisibilityPattern::Stratified, discontinuities, placement, samples);
    if (stratified)
      stratified->source = "as stratified: Owen-scrambled base 2 at N = 2^m; " + stratified->source;
    return stratified;
  }

  if (placement == DiscontinuityPlacement::Independent) {
    // Several discontinuities may share a stratum; only stratified sampling has a closed form:
    // given the visibility function, stratum s contributes an independent error of variance
    // f_s(1-f_s)/N^2, and a stratum holds j ~ Binomial(k, 1/N) uniform discontinuities.
    if (pattern != VisibilityPattern::Stratified) return std::nullopt;
    double per_stratum = 0;
    for (int j = 1; j <= k; ++j)
      per_stratum += binomial_probability(k, j, 1.0 / n) * expected_visibility_sample_variance(j);
    return PredictedError{n * per_stratum / n2, "sum_j Binom(j; k, 1/N) m(j+1-m)/((j+1)(j+2)) / N",
                          "Eq. 11-12 per stratum, strata independent"};
  }

  // Distinct strata. The error is a sum over the strata holding a discontinuity of
  // sigma_i (H(y_i - a_i) - y_i)/N (Eq. 9, 15), sigma_i = +-1 alternating along the light, y_i
  // the discontinuity's and a_i the sample's fraction of the stratum. Over uniform y_i a term
  // has mean sigma_i (1/2 - a_i) and second moment (a_i^3 + (1 - a_i)^3)/3 (Eq. 11).
  switch (pattern) {
    case VisibilityPattern::Uniform:
      // a = 1/2: each term has mean 0 and variance 1/12 (Fig. 4).
      return PredictedError{k / (12 * n2), "k/(12 N^2)", "Fig. 4 (k=1), Fig. 7a"};
    case VisibilityPattern::Stratified:
      // a uniform, independent per stratum: 1/6 per term, uncorrelated (Eq. 12, Fig. 6).
      return PredictedError{k / (6 * n2), "k/(6 N^2)", "Eq. 12, Fig. 6, Fig. 7a"};
    case VisibilityPattern::UniformJitter:
      // One a = gamma for all strata: given gamma, the variance per term is
      // (gamma^3 + (1-gamma)^3)/3 - (1/2-gamma)^2 (1/12 on average) and the alternating means
      // cancel in pairs, leaving (1/2 - gamma)^2 (1/12 on average) for an odd k (Eq. 18, Sec.
      // 4.2.2): (k + (k mod 2))/12.
      return PredictedError{(k + (odd ? 1 : 0)) / (12 * n2), "(k + k mod 2)/(12 N^2)",
                            "Eq. 17-18, Fig. 6, Sec. 4.2.2"};
    case VisibilityPattern::CanonicalHalton: {
      // h(1..N) at N = 2^m is {1/N, ..., (N-1)/N} (stratum left ends, a = 0) plus h(N) = 1/(2N)
      // (stratum 0's centre). Every term has variance 1/12; the means are 1/2 except stratum
      // 0's, which is 0, and alternate in sign. Stratum 0, chosen with probability k/N, is the
      // first discontinuity, so the means leave 1/4 for an odd count of the other terms.
      if (!is_power_of_two(samples)) return std::nullopt;
      double p0 = k / n;
      double leftover = (1 - p0) * (odd ? 0.25 : 0.0) + p0 * (odd ? 0.0 : 0.25);
      return PredictedError{(k / 12.0 + leftover) / n2,
                            "(k/12 + [k odd](1-k/N)/4 + [k even](k/N)/4)/N^2",
                            "Eq. 11 with a = 0 (Sec. 4.1, Fig. 3), N = 2^m"};
    }
    case VisibilityPattern::StratumEnds:
      // a = 0 in every stratum: variance 1/12 and mean 1/2 per term, the alternating means
      // leave 1/4 for an odd k. k = 1: 1/(3N^2), Fig. 4's end-points row.
      return PredictedError{(k / 12.0 + (odd ? 0.25 : 0.0)) / n2, "(k/12 + [k odd]/4)/N^2",
                            "Fig. 4 (k=1), Eq. 11 with a = 0"};
    case VisibilityPattern::Halton:
    case VisibilityPattern::Random:
      break;
  }
  return std::nullopt;
}

VisibilityErrorResult run_visibility_experiment(const VisibilityExperiment& experiment) {
  check_counts(experiment.discontinuities, experiment.placement, experiment.samples);
  if (experiment.trials < 2)
    throw std::invalid_argument("visibility experiment: need at least 2 trials, got " +
                                std::to_string(experiment.trials));

  // The squared error of every trial, trials split in contiguous blocks over the threads.
  std::vector<double> squared_errors(size_t(experiment.trials));
  auto run_trials = [&](int first, int last) {
    std::vector<double> samples(size_t(experiment.samples));
    for (int trial = first; trial < last; ++trial) {
      StreamKey sample_key{experiment.seed, uint64_t(trial), 0, kSampleStream};
      StreamKey discontinuity_key{experiment.seed, uint64_t(trial), 0, kDiscontinuityStream};
      VisibilityFunction visibility = random_visibility_function(
          experiment.discontinuities, experiment.placement, experiment.samples, discontinuity_key);
      generate_visibility_samples(experiment.pattern, sample_key, samples);
      double error = visibility.integral() - estimate_visibility_integral(visibility, samples);
      squared_errors[size_t(trial)] = error * error;
    }
  };
  int threads = experiment.threads > 0 ? experiment.threads
                                       : int(std::max(1u, std::thread::hardware_concurrency()));
  threads = std::clamp(threads, 1, std::max(1, experiment.trials / 256));
  if (threads == 1) {
    run_trials(0, experiment.trials);
  } else {
    std::vector<std::thread> workers;
    for (int t = 0; t < threads; ++t)
      workers.emplace_back(run_trials, int(int64_t(experiment.trials) * t / threads),
                           int(int64_t(experiment.trials) * (t + 1) / threads));
    for (std::thread& worker : workers) worker.join();
  }

  // Mean and variance of the squared error over the trials (Welford), in trial order.
  double mean = 0, sum_squared_deviation = 0;
  for (size_t trial = 0; trial < squared_errors.size(); ++trial) {
    double delta = squared_errors[trial] - mean;
    mean += delta / double(trial + 1);
    sum_squared_deviation += delta * (squared_errors[trial] - mean);
  }

  VisibilityErrorResult result;
  result.experiment = experiment;
  result.mean_squared_error = mean;
  result.standard_error =
      std::sqrt(sum_squared_deviation / (experiment.trials - 1) / experiment.trials);
  result.predicted = predicted_squared_error(experiment.pattern, experiment.discontinuities,
                                             experiment.placement, experiment.samples);
  if (result.predicted && result.predicted->value > 0)
    result.ratio = result.mean_squared_error / result.predicted->value;
  return result;
}

}  // namespace penumbra
