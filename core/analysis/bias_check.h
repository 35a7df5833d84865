#pragma once
// Is a method biased? k independent renders of a scene are z-tested against a reference, block
// by block (`penumbra verify`, core/analysis/verify.h).
//
// For every block of b x b pixels and every colour channel, with m_j the block's mean in run j
// (j = 1..k) and R the reference's block mean:
//
//   M   = (1/k) sum_j m_j                               the runs' mean
//   s_w = sqrt(sum_j V_j) / k,  V_j = sum_p var_j(p) / n^2   from the runs' own variance layers
//                                                       (variance of each pixel's mean; n pixels)
//   s_b = sqrt(sum_j (m_j - M)^2 / (k - 1) / k)         from the spread between the runs
//   s_R = sqrt(sum_p var_R(p)) / n                      the reference's own noise
//   z   = (M - R) / sqrt(max(s_w, s_b)^2 + s_R^2 + f^2),  f = 1e-6 |R| + 1e-9
//
// An unbiased method has E[M] = E[R], and M - R is close to normal (a mean over k n spp samples),
// so |z| > 5 happens by chance with probability 5.7e-7 per test. The variance layers give s_w
// with many degrees of freedom; taking the larger of s_w and s_b guards against a run whose
// variance layer underestimates its noise (rare large samples). f is the storage floor: images
// are float, so two images of one expectation agree to about 1e-7 relative, never better.
//
// Many tests are made at once (blocks x channels), so a flag means something only against the
// chance of any flag: by Bonferroni's inequality, with T tests the probability that an unbiased
// method shows one or more blocks beyond 5 sigma is at most T x 5.7e-7 (1.8e-3 for 3072 tests),
// whatever the correlation between blocks. A flag is therefore strong evidence of bias; no flag
// means only that no bias larger than about 5 standard errors exists in any block (the resolution
// the result reports).
//
// The bound assumes each block's M - R is close to normal, which needs enough samples to hit
// what carries the block's light. An estimator that rarely finds the light (BSDF sampling of a
// light of 1e-8 sr) gives runs that are all zero, or whose variance layers miss the rare large
// samples: all-zero blocks without any noise in the runs are reported as inconclusive, not as
// flags; the others can flag an unbiased method whose budget is too small for its tails.
//
// Blocks whose reference and runs are all zero (black background, no light) carry no test.

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "core/image/image.h"
#include "core/render/film.h"

namespace penumbra {

struct BiasCheckOptions {
  int block_size = 8;  // pixels per side (edge blocks may be smaller)
  double sigma = 5;    // flag |z| above this
};

struct BlockTest {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // [x0, x1) x [y0, y1)
  int channel = 0;                     // 0 R, 1 G, 2 B
  double estimate = 0;                 // M
  double reference = 0;                // R
  double standard_error = 0;           // the denominator of z
  double z = 0;
  // The share of the reference's camera samples in the block with the closed form (1: exact up
  // to antialiasing), or -1 when the reference has no such layer.
  double exact_share = -1;
};

struct BiasCheckResult {
  int runs = 0;
  int width = 0, height = 0, block_size = 0;
  double sigma = 5;
  int blocks = 0;  // blocks of the image
  int tests = 0;   // block-channel tests made (blocks with any signal, times channels)
  std::vector<BlockTest> flagged;  // |z| > sigma, largest |z| first
  // Tests whose runs carry no noise at all (zero variance layers, identical means) but differ
  // from the reference: nothing can be said at this budget (e.g. no sample found the light).
  std::vector<BlockTest> inconclusive;
  BlockTest worst;                      // the largest |z| of every test
  double per_test_false_alarm = 0;      // two-sided normal tail at sigma
  double family_false_alarm_bound = 0;  // min(1, tests x per_test_false_alarm)
  // The median over the tests of standard_error / |R| (tests with R != 0): a relative bias of
  // about sigma times this in a typical block would be flagged.
  double median_relative_error = 0;
  bool passed() const { return flagged.empty(); }
};

// `reference` is the reference film (mean and variance of the mean per pixel); `exact_fraction`
// (may be null or empty) the share of exact camera samples per pixel. Every run must have the
// reference's resolution; at least two runs. Throws std::invalid_argument naming what is wrong.
BiasCheckResult check_bias(const Film& reference, const Image* exact_fraction,
                           std::span<const Film> runs, const BiasCheckOptions& options = {});

// Two-sided tail 2 (1 - Phi(sigma)) of the standard normal.
double normal_two_sided_tail(double sigma);

// The result as text: the verdict with its Bonferroni bound, the resolution, the worst block
// and up to `max_listed` flagged blocks. `what` names the method and scene.
std::string bias_check_text(const BiasCheckResult& result, const std::string& what,
                            int max_listed = 10);
// The result as JSON ("format": "penumbra/verify-result@1").
std::string bias_check_json(const BiasCheckResult& result, const std::string& scene,
                            const std::string& method);

}  // namespace penumbra
