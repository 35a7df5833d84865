#pragma once
// Peters 2021, Sec. 4.2-4.3: combining projected solid angle sampling (diffuse, technique 0)
// and LTC sampling (specular, technique 1) of a polygon light. Free functions of the
// techniques' densities at a sample's point and of the unshadowed integrals c_j; nothing here
// knows about scenes.
//
// Notation. p_j(x): the density of technique j at the point x (any common measure; area
// measure in Penumbra's strategies). c_j: the unshadowed shading technique j stands for,
//   c_j = L_e a_j integral over the light of p_{M_j}(w) dw        (Sec. 4.2),
// per colour channel (a_0 the diffuse albedo, clamped to at least 0.01 per channel as Peters
// advises, a_1 the specular albedo; see ltc_unshadowed_shading.h).
//
// Heuristics (weights per colour channel; each set sums to 1 wherever some p_j > 0):
//   balance                w_j = p_j / sum_k p_k                              (Veach)
//   weighted balance       w_j = c_j p_j / sum_k c_k p_k                      (Sec. 4.2)
//   clamped optimal        w_j = v w_j^weighted + (1 - v) w_j^balance, v = 1/2 (Sec. 4.3)
// Where sum_k c_k p_k = 0 in a channel (no light in that channel) the weighted heuristic falls
// back to balance there, so weights never divide by zero.
//
// Estimator with n_j samples x_{j,i} of technique j (Veach's multi-sample MIS):
//   F = sum_j (1 / n_j) sum_i w_j(x_{j,i}) f(x_{j,i}) / p_j(x_{j,i}),
// f = L_e f_r cos V G (area measure). Per sample it needs: the integrand f(x) (zero when
// occluded), and BOTH techniques' densities at x (p_0(x), p_1(x)); per shading point and light
// it needs c_0 and c_1 (one closed-form evaluation each, no rays) and the counts n_j.
// Counts: balance uses n_k p_k (Veach); the weighted heuristic does NOT use them: with
// w_j = c_j p_j / sum_k c_k p_k and f exactly sum_k c_k p_k (unoccluded, BRDF equal to its LTC
// fit), every sample of technique j contributes c_j / n_j, so F = c_0 + c_1 for every set of
// samples whatever the counts: zero variance (Sec. 4.2: "generalizing to different sample
// counts is trivial").

#include <array>
#include <optional>
#include <span>

#include "core/math/vec.h"

namespace penumbra {

enum class PetersHeuristic { Balance, Weighted, ClampedOptimal };

// Peters' blend parameter v of Sec. 4.3 (his experiments and ours use 1/2).
inline constexpr double kClampedOptimalBlend = 0.5;

inline constexpr int kPetersTechniques = 2;  // 0: psa (diffuse), 1: ltc (specular)
using TechniqueDensities = std::array<double, kPetersTechniques>;
using UnshadowedIntegrals = std::array<Rgb, kPetersTechniques>;
using TechniqueCounts = std::array<int, kPetersTechniques>;  // n_j, samples per technique

// Balance heuristic weight of technique j, n_j p_j / sum_k n_k p_k (0 where every density is 0).
double balance_weight(int j, const TechniqueDensities& pdfs,
                      const TechniqueCounts& counts = {1, 1});
// Sec. 4.2, per channel.
Rgb weighted_balance_weight(int j, const TechniqueDensities& pdfs,
                            const UnshadowedIntegrals& unshadowed);
// Sec. 4.3, per channel; v in [0, 1].
Rgb clamped_optimal_weight(int j, const TechniqueDensities& pdfs,
                           const UnshadowedIntegrals& unshadowed, double v = kClampedOptimalBlend,
                           const TechniqueCounts& counts = {1, 1});
// Dispatch on the heuristic (v is used by ClampedOptimal only).
Rgb peters_mis_weight(PetersHeuristic heuristic, int j, const TechniqueDensities& pdfs,
                      const UnshadowedIntegrals& unshadowed, double v = kClampedOptimalBlend,
                      const TechniqueCounts& counts = {1, 1});

// What one technique's sample brings to the combination.
struct TechniqueSample {
  Rgb integrand{0, 0, 0};         // f(x_j) = L_e f_r cos V G at the sampled point (0 if occluded)
  TechniqueDensities pdfs{0, 0};  // p_0(x_j), p_1(x_j), same measure as the integrand's
};

// One sample's term of F before the 1 / n_j: w_j(x) f(x) / p_j(x) for a sample x of technique j
// with its densities s.pdfs (the estimator sums these and divides by n_j). 0 where p_j(x) = 0 or
// anything is not finite. `counts` enter the balance part only (see above).
Rgb peters_sample_contribution(int j, const TechniqueSample& s,
                               const UnshadowedIntegrals& unshadowed, PetersHeuristic heuristic,
                               double v = kClampedOptimalBlend,
                               const TechniqueCounts& counts = {1, 1});

// F for one sample of psa (index 0) and one of ltc (index 1); an empty sample (the technique drew
// nothing) contributes 0. Always finite.
Rgb combine_psa_ltc(const std::array<std::optional<TechniqueSample>, kPetersTechniques>& samples,
                    const UnshadowedIntegrals& unshadowed, PetersHeuristic heuristic,
                    double v = kClampedOptimalBlend);
// F for n_0 = psa_samples.size() samples of psa and n_1 = ltc_samples.size() of ltc (empty
// entries are samples that drew nothing: they count in n_j and contribute 0). Always finite.
Rgb combine_psa_ltc(std::span<const std::optional<TechniqueSample>> psa_samples,
                    std::span<const std::optional<TechniqueSample>> ltc_samples,
                    const UnshadowedIntegrals& unshadowed, PetersHeuristic heuristic,
                    double v = kClampedOptimalBlend);

}  // namespace penumbra
