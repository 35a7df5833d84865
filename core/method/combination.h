#pragma once
// The combinations of a method (`/balance`, `/power`, `/avg`, `/smooth`, `/smooth-fixed`,
// `/weighted`, `/clamped-optimal`): free functions of the terms' densities at one sample's point.
// Nothing here knows about scenes, lights or strategies; core/method/direct_lighting.cpp
// evaluates the densities and calls these.
//
// Notation. A method has T terms; term k draws n_k samples with density p_k (area measure in
// Penumbra's strategies; any common measure works). The "scaled density" of term k at a point x
// is q_k = n_k p_k(x). The estimator is Veach's multi-sample MIS,
//   F = sum_k (1 / n_k) sum_i w_k(x_{k,i}) f(x_{k,i}) / p_k(x_{k,i}),
// unbiased whenever the weights of all terms at every point sum to one where f != 0 (and a
// term's weight is 0 where it cannot draw the point).
//
// Heuristics on scaled densities (each weight set sums to 1 wherever some q_k > 0, and is 0
// where none is, or where the sum is not finite: no weight is ever NaN):
//   balance   w_i = q_i / sum_k q_k                                    (Veach Eq. 9.8)
//   power     w_i = q_i^2 / sum_k q_k^2                                (Veach's beta = 2)
//   avg       w_i = 1 / T                                              (plain average)
//   smoothed  balance over q'_k = s q_k for the eased terms, q'_k = q_k for the others, with
//             s in [0, 1] the smoothing factor at the point (Salesin & Jarosz Eq. 22; the factor
//             itself, Eq. 23-24, is core/method/smoothing.h); where every q'_k is 0 the plain
//             balance weights keep the sum at one. `smooth` and `smooth-fixed` differ only in
//             the factor.
//
// Peters 2021, Sec. 4.2-4.3: combining projected solid angle sampling (diffuse, technique 0)
// and LTC sampling (specular, technique 1) of a polygon light, with the unshadowed integrals
// c_j of the shading point and light (core/method/unshadowed_integrals.h):
//   c_j = L_e a_j integral over the light of p_{M_j}(w) dw        (Sec. 4.2),
// per colour channel (a_0 the diffuse albedo, clamped to at least 0.01 per channel as Peters
// advises, a_1 the specular albedo).
// Heuristics (weights per colour channel; each set sums to 1 wherever some p_j > 0):
//   balance                w_j = n_j p_j / sum_k n_k p_k                      (Veach)
//   weighted balance       w_j = c_j p_j / sum_k c_k p_k                      (Sec. 4.2)
//   clamped optimal        w_j = v w_j^weighted + (1 - v) w_j^balance, v = 1/2 (Sec. 4.3)
// Where sum_k c_k p_k = 0 in a channel (no light in that channel) the weighted heuristic falls
// back to balance there, so weights never divide by zero.
// Per sample Peters' heuristics need the integrand f(x) (zero when occluded) and BOTH
// techniques' densities at x; per shading point and light c_0, c_1 (one closed-form evaluation
// each, no rays) and the counts n_j. Counts: balance uses n_k p_k (Veach); the weighted
// heuristic does NOT use them: with w_j = c_j p_j / sum_k c_k p_k and f exactly sum_k c_k p_k
// (unoccluded, BRDF equal to its LTC fit), every sample of technique j contributes c_j / n_j,
// so F = c_0 + c_1 for every set of samples whatever the counts: zero variance (Sec. 4.2:
// "generalizing to different sample counts is trivial").

#include <array>
#include <cstddef>
#include <optional>
#include <span>

#include "core/math/vec.h"

namespace penumbra {

// --- Heuristics on the scaled densities q_k = n_k p_k of T terms ---------------------------

double balance_weight(std::span<const double> scaled_pdfs, size_t term);
double power_weight(std::span<const double> scaled_pdfs, size_t term);
double average_weight(size_t term_count);
// `eased[k]`: term k's density is multiplied by `factor` (Salesin & Jarosz: the BSDF terms).
double smoothed_balance_weight(std::span<const double> scaled_pdfs, std::span<const bool> eased,
                               double factor, size_t term);

// --- Peters 2021: psa (technique 0) and ltc (technique 1), per colour channel ----------------

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
