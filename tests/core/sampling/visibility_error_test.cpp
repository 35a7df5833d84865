// The patterns as estimators: the expected squared error of estimating the integral of a binary
// visibility function on a linear light, over random discontinuity positions, against the closed
// forms of Ramamoorthi et al. 2012 (Sec. 4, Figs. 4 and 6), within 5%.
//
// One discontinuity at t ~ U(0,1) (visibility [x >= t]):   uniform 1/(12 N^2), stratified and
//   uniform-jitter 1/(6 N^2), random E[t(1-t)]/N = 1/(6 N).
// Two discontinuities in different strata (visibility [t1 <= x < t2]): uniform and uniform-jitter
//   1/(6 N^2), stratified 1/(3 N^2).

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "core/sampling/counter_random.h"
#include "core/sampling/pattern.h"

namespace penumbra {
namespace {

constexpr uint32_t kTrials = 40000;

// Mean squared error of the N-sample estimate of the integral of [t1 <= x < t2] over [0,1), with
// the samples taken from the x coordinate of a 2D pattern on a thin light (aspect >= N gives the
// N x 1 grid) or from the 1D pattern.
double mean_squared_error(Pattern pattern, uint32_t n, int discontinuities, bool use_2d) {
  double sum = 0.0;
  std::vector<double> xs(n);
  std::vector<Vec2> points(n);
  StreamRandom positions({777, n, 0, 0});
  for (uint32_t trial = 0; trial < kTrials; ++trial) {
    double t1 = 0.0, t2 = 1.0;
    if (discontinuities == 1) {
      t1 = positions.uniform(trial, 0);
    } else {
      // Two positions in different strata (redraw while they share one).
      for (uint32_t attempt = 0;; ++attempt) {
        double a = positions.uniform(trial, 2 * attempt);
        double b = positions.uniform(trial, 2 * attempt + 1);
        t1 = std::min(a, b);
        t2 = std::max(a, b);
        if (static_cast<uint32_t>(t1 * n) != static_cast<uint32_t>(t2 * n)) break;
      }
    }
    StreamKey key{4242, trial, 0, n};
    if (use_2d) {
      generate_2d(pattern, key, 4.0 * n, points);
      for (uint32_t i = 0; i < n; ++i) xs[i] = points[i].x;
    } else {
      generate_1d(pattern, key, xs);
    }
    uint32_t visible = 0;
    for (double x : xs) visible += (x >= t1 && x < t2) ? 1 : 0;
    double error = static_cast<double>(visible) / n - (t2 - t1);
    sum += error * error;
  }
  double mse = sum / kTrials;
  std::printf("%-14s N=%2u %s discontinuities=%d: MSE * N^2 = %.4f\n",
              std::string(pattern_name(pattern)).c_str(), n, use_2d ? "2D" : "1D", discontinuities,
              mse * n * n);
  return mse;
}

TEST(VisibilityError, OneDiscontinuityMatchesRamamoorthi) {
  for (uint32_t n : {4u, 8u, 16u}) {
    double n2 = static_cast<double>(n) * n;
    for (bool use_2d : {false, true}) {
      EXPECT_NEAR(mean_squared_error(Pattern::Uniform, n, 1, use_2d) * 12 * n2, 1.0, 0.05);
      EXPECT_NEAR(mean_squared_error(Pattern::Stratified, n, 1, use_2d) * 6 * n2, 1.0, 0.05);
      EXPECT_NEAR(mean_squared_error(Pattern::UniformJitter, n, 1, use_2d) * 6 * n2, 1.0, 0.05);
      EXPECT_NEAR(mean_squared_error(Pattern::Random, n, 1, use_2d) * 6 * n, 1.0, 0.05);
    }
  }
}

TEST(VisibilityError, TwoDiscontinuitiesMatchRamamoorthi) {
  for (uint32_t n : {4u, 8u, 16u}) {
    double n2 = static_cast<double>(n) * n;
    for (bool use_2d : {false, true}) {
      EXPECT_NEAR(mean_squared_error(Pattern::Uniform, n, 2, use_2d) * 6 * n2, 1.0, 0.05);
      EXPECT_NEAR(mean_squared_error(Pattern::UniformJitter, n, 2, use_2d) * 6 * n2, 1.0, 0.05);
      EXPECT_NEAR(mean_squared_error(Pattern::Stratified, n, 2, use_2d) * 3 * n2, 1.0, 0.05);
    }
  }
}

TEST(VisibilityError, CmjAndScrambledSequencesBeatRandom) {
  // No closed form here; a stratified pattern must at least beat independent samples by a wide
  // margin at N = 16 (random: 1/(6N) = 0.0104; stratified: 1/(6N^2) = 0.00065).
  for (Pattern pattern : {Pattern::Cmj, Pattern::Halton, Pattern::Sobol}) {
    for (bool use_2d : {false, true}) {
      EXPECT_LT(mean_squared_error(pattern, 16, 1, use_2d), 2.0 / (6.0 * 16 * 16))
          << pattern_name(pattern);
    }
  }
}

}  // namespace
}  // namespace penumbra
