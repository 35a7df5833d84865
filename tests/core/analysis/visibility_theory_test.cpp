// Ramamoorthi et al. 2012, Sec. 4 on the visibility function alone: the function and its
// estimate on hand examples, the distribution of random discontinuities (chi-square), and the
// measured expected squared error of every pattern against the closed forms of Figs. 4, 6, 7.
//
// Tolerance: a measured error must be within 5% of its formula (|ratio - 1| < 0.05). With the
// trial counts here the standard error of each measurement is about 1% (checked below), so 5% is
// 4-5 standard errors: a wrong formula or a wrong pattern (e.g. stratified instead of uniform
// jitter, a factor 2) cannot pass, and the fixed seeds make the test deterministic.

#include "core/analysis/visibility_theory.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <vector>

#include "core/analysis/visibility_reproduction.h"
#include "core/image/metrics.h"

namespace penumbra {
namespace {

constexpr double kTolerance = 0.05;
constexpr double kMaxRelativeStandardError = 0.015;

void expect_matches_prediction(const VisibilityErrorResult& row) {
  const VisibilityExperiment& e = row.experiment;
  std::string what = std::string(visibility_pattern_name(e.pattern)) + " " +
                     std::string(placement_name(e.placement)) +
                     " k=" + std::to_string(e.discontinuities) + " N=" + std::to_string(e.samples);
  ASSERT_TRUE(row.predicted) << what;
  ASSERT_TRUE(row.ratio) << what;
  EXPECT_TRUE(std::isfinite(row.mean_squared_error)) << what;
  EXPECT_LT(row.standard_error / row.mean_squared_error, kMaxRelativeStandardError) << what;
  EXPECT_NEAR(*row.ratio, 1.0, kTolerance)
      << what << ": measured " << row.mean_squared_error << ", predicted " << row.predicted->value
      << " (" << row.predicted->formula << ")";
}

const VisibilityErrorResult& find_row(const VisibilityTable& table, VisibilityPattern pattern,
                                      int k = -1) {
  for (const auto& row : table.rows)
    if (row.experiment.pattern == pattern && (k < 0 || row.experiment.discontinuities == k))
      return row;
  throw std::runtime_error("row not found");
}

TEST(VisibilityFunction, IntegralVisibilityAndEstimateOnAHandExample) {
  // Hidden on [0, 0.2), visible on [0.2, 0.5), hidden on [0.5, 0.7), visible on [0.7, 1).
  VisibilityFunction v{false, {0.2, 0.5, 0.7}};
  EXPECT_NEAR(v.integral(), 0.6, 1e-15);
  EXPECT_FALSE(v.visible(0.1));
  EXPECT_TRUE(v.visible(0.2));
  EXPECT_TRUE(v.visible(0.3));
  EXPECT_FALSE(v.visible(0.6));
  EXPECT_TRUE(v.visible(0.99));
  std::vector<double> samples{0.1, 0.3, 0.6, 0.8};
  EXPECT_EQ(estimate_visibility_integral(v, samples), 0.5);
  VisibilityFunction complement{true, {0.2, 0.5, 0.7}};
  EXPECT_NEAR(complement.integral(), 0.4, 1e-15);
  EXPECT_EQ(estimate_visibility_integral(complement, samples), 0.5);
  EXPECT_EQ((VisibilityFunction{true, {}}.integral()), 1.0);
  EXPECT_EQ((VisibilityFunction{false, {}}.integral()), 0.0);
  EXPECT_EQ(estimate_visibility_integral(v, {}), 0.0);
}

TEST(VisibilityFunction, RandomDiscontinuitiesInDistinctStrata) {
  const int n = 16;
  for (uint64_t trial = 0; trial < 500; ++trial) {
    StreamKey key{3, trial, 0, 1};
    for (int k : {1, 2, 7, 16}) {
      VisibilityFunction v =
          random_visibility_function(k, DiscontinuityPlacement::DistinctStrata, n, key);
      ASSERT_EQ(int(v.discontinuities.size()), k);
      EXPECT_TRUE(std::is_sorted(v.discontinuities.begin(), v.discontinuities.end()));
      std::vector<int> strata;
      for (double d : v.discontinuities) {
        ASSERT_GE(d, 0.0);
        ASSERT_LT(d, 1.0);
        strata.push_back(int(d * n));
      }
      EXPECT_EQ(std::unique(strata.begin(), strata.end()), strata.end()) << "shared stratum";
      // Same key, same function.
      VisibilityFunction again =
          random_visibility_function(k, DiscontinuityPlacement::DistinctStrata, n, key);
      EXPECT_EQ(again.discontinuities, v.discontinuities);
      EXPECT_EQ(again.visible_at_start, v.visible_at_start);
    }
  }
  EXPECT_THROW(random_visibility_function(17, DiscontinuityPlacement::DistinctStrata, 16, {}),
               std::invalid_argument);
  EXPECT_THROW(random_visibility_function(-1, DiscontinuityPlacement::Independent, 16, {}),
               std::invalid_argument);
}

// Chi-square of pooled positions against the uniform density on [0,1) (both placements promise
// uniform marginals), 32 bins, 31 degrees of freedom; 61.1 is the 0.999 quantile.
TEST(VisibilityFunction, DiscontinuityPositionsAreUniform) {
  for (auto placement :
       {DiscontinuityPlacement::DistinctStrata, DiscontinuityPlacement::Independent}) {
    const int bins = 32, k = 3, n = 8, trials = 8000;
    std::vector<double> counts(bins, 0);
    int starts_visible = 0;
    for (int t = 0; t < trials; ++t) {
      VisibilityFunction v =
          random_visibility_function(k, placement, n, StreamKey{5, uint64_t(t), 0, 1});
      for (double d : v.discontinuities) counts[std::min(int(d * bins), bins - 1)] += 1;
      starts_visible += v.visible_at_start ? 1 : 0;
    }
    double expected = double(trials) * k / bins, chi_square = 0;
    for (double c : counts) chi_square += (c - expected) * (c - expected) / expected;
    EXPECT_LT(chi_square, 61.1) << placement_name(placement);
    // The start state is a fair coin: within 4 standard deviations.
    EXPECT_NEAR(starts_visible, trials / 2, 4 * std::sqrt(trials / 4.0));
  }
}

TEST(VisibilityPatterns, CanonicalHaltonIsThePapersSequence) {
  std::vector<double> points(4);
  generate_visibility_samples(VisibilityPattern::CanonicalHalton, {}, points);
  EXPECT_EQ(points, (std::vector<double>{0.5, 0.25, 0.75, 0.125}));  // Sec. 4.1
  generate_visibility_samples(VisibilityPattern::StratumEnds, {}, points);
  EXPECT_EQ(points, (std::vector<double>{0.0, 0.25, 0.5, 0.75}));
}

TEST(VisibilityTheory, NoDiscontinuityHasNoError) {
  VisibilityErrorResult result = run_visibility_experiment(
      {VisibilityPattern::Random, 0, DiscontinuityPlacement::Independent, 8, 100, 1});
  EXPECT_EQ(result.mean_squared_error, 0.0);
  EXPECT_EQ(result.standard_error, 0.0);
  ASSERT_TRUE(result.predicted);
  EXPECT_EQ(result.predicted->value, 0.0);
  EXPECT_FALSE(result.ratio);
}

TEST(VisibilityTheory, ResultsAreDeterministic) {
  VisibilityExperiment experiment{
      VisibilityPattern::Stratified, 3, DiscontinuityPlacement::DistinctStrata, 16, 500, 42};
  EXPECT_EQ(run_visibility_experiment(experiment).mean_squared_error,
            run_visibility_experiment(experiment).mean_squared_error);
  // The thread count does not change a bit.
  experiment.trials = 3000;
  experiment.threads = 1;
  VisibilityErrorResult one_thread = run_visibility_experiment(experiment);
  experiment.threads = 3;
  VisibilityErrorResult three_threads = run_visibility_experiment(experiment);
  EXPECT_EQ(one_thread.mean_squared_error, three_threads.mean_squared_error);
  EXPECT_EQ(one_thread.standard_error, three_threads.standard_error);
  experiment.seed = 43;
  VisibilityErrorResult other = run_visibility_experiment(experiment);
  experiment.seed = 42;
  EXPECT_NE(other.mean_squared_error, run_visibility_experiment(experiment).mean_squared_error);
}

// Fig. 4: end-points 1/(3N^2), uniform 1/(12N^2), stratified and uniform jitter 1/(6N^2), canonical
// Halton close to the end-point case, random 1/(6N).
TEST(VisibilityTheory, OneDiscontinuityMatchesFig4) {
  VisibilityReproductionOptions options{32, 20000, 4};
  VisibilityTable table = reproduce_one_discontinuity(options);
  ASSERT_EQ(table.rows.size(), 7u);
  for (const auto& row : table.rows) expect_matches_prediction(row);
  double n2 = 32.0 * 32.0;
  EXPECT_DOUBLE_EQ(find_row(table, VisibilityPattern::StratumEnds).predicted->value, 1 / (3 * n2));
  EXPECT_DOUBLE_EQ(find_row(table, VisibilityPattern::Uniform).predicted->value, 1 / (12 * n2));
  EXPECT_DOUBLE_EQ(find_row(table, VisibilityPattern::Stratified).predicted->value, 1 / (6 * n2));
  EXPECT_DOUBLE_EQ(find_row(table, VisibilityPattern::UniformJitter).predicted->value,
                   1 / (6 * n2));
  EXPECT_DOUBLE_EQ(find_row(table, VisibilityPattern::Random).predicted->value, 1 / (6 * 32.0));
  EXPECT_NEAR(find_row(table, VisibilityPattern::CanonicalHalton).predicted->value * n2, 1 / 3.0,
              0.01);
}

// Fig. 6: two discontinuities in different strata: uniform and uniform jitter 1/(6N^2),
// stratified 1/(3N^2): uniform jitter halves stratified's error.
TEST(VisibilityTheory, TwoDiscontinuitiesMatchFig6) {
  VisibilityReproductionOptions options{32, 20000, 6};
  VisibilityTable table = reproduce_two_discontinuities(options);
  for (const auto& row : table.rows) expect_matches_prediction(row);
  double n2 = 32.0 * 32.0;
  EXPECT_DOUBLE_EQ(find_row(table, VisibilityPattern::Uniform).predicted->value, 1 / (6 * n2));
  EXPECT_DOUBLE_EQ(find_row(table, VisibilityPattern::UniformJitter).predicted->value,
                   1 / (6 * n2));
  EXPECT_DOUBLE_EQ(find_row(table, VisibilityPattern::Stratified).predicted->value, 1 / (3 * n2));
  double stratified_over_jitter =
      find_row(table, VisibilityPattern::Stratified).mean_squared_error /
      find_row(table, VisibilityPattern::UniformJitter).mean_squared_error;
  EXPECT_NEAR(stratified_over_jitter, 2.0, 0.2);
}

// Fig. 7a: k = 1..7: uniform k/12, stratified k/6, uniform jitter (k + k mod 2)/12, canonical
// Halton larger for odd k than for the even k around it.
TEST(VisibilityTheory, DiscontinuityCountMatchesFig7a) {
  VisibilityReproductionOptions options{32, 16000, 7};
  VisibilityTable table = reproduce_discontinuity_count(options, 7);
  ASSERT_EQ(table.rows.size(), 35u);
  for (const auto& row : table.rows) expect_matches_prediction(row);
  for (int k = 1; k <= 7; ++k) {
    const auto& jitter = find_row(table, VisibilityPattern::UniformJitter, k);
    EXPECT_NEAR(jitter.predicted->value * 32 * 32, (k + k % 2) / 12.0, 1e-12);
  }
  for (int k : {3, 5}) {
    double odd = find_row(table, VisibilityPattern::CanonicalHalton, k).normalized_error();
    double next_even =
        find_row(table, VisibilityPattern::CanonicalHalton, k + 1).normalized_error();
    EXPECT_GT(odd, next_even) << "Halton is non-monotonic: odd k " << k;
  }
}

// Fig. 7b: with several discontinuities per stratum the analysis no longer holds and every
// pattern approaches stratified sampling, whose error keeps a closed form.
TEST(VisibilityTheory, ExtremeCaseApproachesStratified) {
  VisibilityReproductionOptions options{16, 12000, 8};
  VisibilityTable table = reproduce_extreme_case(options);
  std::map<std::pair<VisibilityPattern, int>, const VisibilityErrorResult*> independent;
  for (const auto& row : table.rows) {
    if (row.predicted) expect_matches_prediction(row);
    if (row.experiment.placement == DiscontinuityPlacement::Independent)
      independent[{row.experiment.pattern, row.experiment.discontinuities}] = &row;
  }
  // 16 discontinuities per stratum on average: within 10% of stratified.
  double stratified = independent.at({VisibilityPattern::Stratified, 256})->mean_squared_error;
  for (auto pattern : {VisibilityPattern::Uniform, VisibilityPattern::UniformJitter,
                       VisibilityPattern::CanonicalHalton})
    EXPECT_NEAR(independent.at({pattern, 256})->mean_squared_error / stratified, 1.0, 0.1)
        << visibility_pattern_name(pattern);
  // One per stratum on average: uniform still clearly below stratified.
  EXPECT_LT(independent.at({VisibilityPattern::Uniform, 16})->mean_squared_error,
            0.8 * independent.at({VisibilityPattern::Stratified, 16})->mean_squared_error);
}

// The convergence rate is N^-2 for the stratified patterns (Sec. 8: "variance decays as 1/N^2 in
// all cases") and N^-1 for random sampling.
TEST(VisibilityTheory, ConvergenceSlopes) {
  VisibilityReproductionOptions options{64, 12000, 9};
  VisibilityTable table = reproduce_convergence(options, 2);
  std::map<VisibilityPattern, std::pair<std::vector<double>, std::vector<double>>> curves;
  for (const auto& row : table.rows) {
    expect_matches_prediction(row);
    curves[row.experiment.pattern].first.push_back(row.experiment.samples);
    curves[row.experiment.pattern].second.push_back(row.mean_squared_error);
  }
  for (auto pattern : {VisibilityPattern::Uniform, VisibilityPattern::UniformJitter,
                       VisibilityPattern::Stratified})
    EXPECT_NEAR(log_log_slope(curves[pattern].first, curves[pattern].second), -2.0, 0.05)
        << visibility_pattern_name(pattern);
  EXPECT_NEAR(log_log_slope(curves[VisibilityPattern::Random].first,
                            curves[VisibilityPattern::Random].second),
              -1.0, 0.05);
}

TEST(VisibilityReproduction, TablesFormatAndChart) {
  VisibilityReproductionOptions options{16, 200, 10};
  VisibilityTable count = reproduce_discontinuity_count(options, 3);
  std::string text = format_visibility_table(count);
  EXPECT_NE(text.find("uniform-jitter"), std::string::npos);
  EXPECT_NE(text.find("(k + k mod 2)/(12 N^2)"), std::string::npos);
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 2 + 15);

  ChartSpec chart = discontinuity_count_chart(count);
  ASSERT_EQ(chart.series.size(), 10u);  // 5 patterns, measured and predicted
  EXPECT_EQ(chart.series[0].x, (std::vector<double>{1, 2, 3}));
  EXPECT_EQ(chart.series[0].color, chart.series[1].color);
  EXPECT_TRUE(chart.series[1].dashed);

  VisibilityTable convergence = reproduce_convergence(options, 1);
  ChartSpec slopes = convergence_chart(convergence);
  ASSERT_EQ(slopes.series.size(), 4u);
  for (const auto& series : slopes.series) ASSERT_TRUE(series.fit) << series.name;

  auto directory = std::filesystem::temp_directory_path();
  std::string path =
      (directory / ("penumbra_visibility_" + std::to_string(::getpid()) + ".png")).string();
  write_line_chart(path, chart);
  EXPECT_GT(std::filesystem::file_size(path), 1000u);
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace penumbra
