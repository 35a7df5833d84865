#include "core/method/combination.h"

#include <algorithm>
#include <cmath>

namespace penumbra {
namespace {

// Where no technique has weight in this channel (sum_k c_k p_k = 0: the light is black in it,
// or only techniques with c_k = 0 reach the point) fall back to balance: weights still sum to 1.
double channel_weighted_balance(int j, const TechniqueDensities& pdfs,
                                const std::array<double, kPetersTechniques>& c) {
  double sum = 0;
  for (int k = 0; k < kPetersTechniques; ++k) sum += std::max(0.0, c[k]) * pdfs[k];
  if (!(sum > 0) || !std::isfinite(sum)) return balance_weight(j, pdfs);
  return std::max(0.0, c[j]) * pdfs[j] / sum;
}

Rgb combine_samples(int j, std::span<const std::optional<TechniqueSample>> samples,
                    const UnshadowedIntegrals& unshadowed, PetersHeuristic heuristic, double v,
                    const TechniqueCounts& counts) {
  Rgb sum{0, 0, 0};
  for (const std::optional<TechniqueSample>& s : samples)
    if (s) sum += peters_sample_contribution(j, *s, unshadowed, heuristic, v, counts);
  return samples.empty() ? sum : sum / double(samples.size());
}

// w_i = x_i / sum_k x_k for non-negative x; 0 where the sum is 0 or not finite.
double normalized_share(std::span<const double> values, size_t term) {
  double sum = 0;
  for (double x : values) sum += x;
  if (!(sum > 0) || !std::isfinite(sum)) return 0;
  return values[term] / sum;
}

}  // namespace

double balance_weight(std::span<const double> scaled_pdfs, size_t term) {
  return normalized_share(scaled_pdfs, term);
}

double power_weight(std::span<const double> scaled_pdfs, size_t term) {
  double sum = 0;
  for (double q : scaled_pdfs) sum += q * q;
  if (!(sum > 0) || !std::isfinite(sum)) return 0;
  return scaled_pdfs[term] * scaled_pdfs[term] / sum;
}

double average_weight(size_t term_count) {
  return term_count > 0 ? 1.0 / double(term_count) : 0.0;
}

double smoothed_balance_weight(std::span<const double> scaled_pdfs, std::span<const bool> eased,
                               double factor, size_t term) {
  auto smoothed = [&](size_t k) { return eased[k] ? scaled_pdfs[k] * factor : scaled_pdfs[k]; };
  double sum = 0;
  for (size_t k = 0; k < scaled_pdfs.size(); ++k) sum += smoothed(k);
  // Where every smoothed density vanishes (only eased terms reach the point, at an edge) the
  // plain balance heuristic keeps the weights summing to one.
  if (!(sum > 0)) return balance_weight(scaled_pdfs, term);
  if (!std::isfinite(sum)) return 0;
  return smoothed(term) / sum;
}

double balance_weight(int j, const TechniqueDensities& pdfs, const TechniqueCounts& counts) {
  std::array<double, kPetersTechniques> scaled;
  for (int k = 0; k < kPetersTechniques; ++k) scaled[k] = counts[k] * pdfs[k];
  return balance_weight(scaled, size_t(j));
}

Rgb weighted_balance_weight(int j, const TechniqueDensities& pdfs,
                            const UnshadowedIntegrals& unshadowed) {
  Rgb weight;
  for (int channel = 0; channel < 3; ++channel) {
    std::array<double, kPetersTechniques> c;
    for (int k = 0; k < kPetersTechniques; ++k) c[k] = unshadowed[k][channel];
    weight[channel] = channel_weighted_balance(j, pdfs, c);
  }
  return weight;
}

Rgb clamped_optimal_weight(int j, const TechniqueDensities& pdfs,
                           const UnshadowedIntegrals& unshadowed, double v,
                           const TechniqueCounts& counts) {
  double balance = balance_weight(j, pdfs, counts);
  return v * weighted_balance_weight(j, pdfs, unshadowed) +
         (1.0 - v) * Rgb{balance, balance, balance};
}

Rgb peters_mis_weight(PetersHeuristic heuristic, int j, const TechniqueDensities& pdfs,
                      const UnshadowedIntegrals& unshadowed, double v,
                      const TechniqueCounts& counts) {
  switch (heuristic) {
    case PetersHeuristic::Balance: {
      double w = balance_weight(j, pdfs, counts);
      return {w, w, w};
    }
    case PetersHeuristic::Weighted:
      return weighted_balance_weight(j, pdfs, unshadowed);
    case PetersHeuristic::ClampedOptimal:
      return clamped_optimal_weight(j, pdfs, unshadowed, v, counts);
  }
  return {0, 0, 0};
}

Rgb peters_sample_contribution(int j, const TechniqueSample& s,
                               const UnshadowedIntegrals& unshadowed, PetersHeuristic heuristic,
                               double v, const TechniqueCounts& counts) {
  double own_pdf = s.pdfs[j];
  if (!(own_pdf > 0) || !std::isfinite(own_pdf) || !is_finite(s.integrand)) return {0, 0, 0};
  Rgb term = peters_mis_weight(heuristic, j, s.pdfs, unshadowed, v, counts) * s.integrand / own_pdf;
  return is_finite(term) ? term : Rgb{0, 0, 0};
}

Rgb combine_psa_ltc(const std::array<std::optional<TechniqueSample>, kPetersTechniques>& samples,
                    const UnshadowedIntegrals& unshadowed, PetersHeuristic heuristic, double v) {
  return combine_psa_ltc({&samples[0], 1}, {&samples[1], 1}, unshadowed, heuristic, v);
}

Rgb combine_psa_ltc(std::span<const std::optional<TechniqueSample>> psa_samples,
                    std::span<const std::optional<TechniqueSample>> ltc_samples,
                    const UnshadowedIntegrals& unshadowed, PetersHeuristic heuristic, double v) {
  TechniqueCounts counts{int(psa_samples.size()), int(ltc_samples.size())};
  // A technique without samples estimates nothing: the others take its part (c = 0 for it).
  UnshadowedIntegrals c = unshadowed;
  for (int k = 0; k < kPetersTechniques; ++k)
    if (counts[k] == 0) c[k] = {0, 0, 0};
  return combine_samples(0, psa_samples, c, heuristic, v, counts) +
         combine_samples(1, ltc_samples, c, heuristic, v, counts);
}

}  // namespace penumbra
