#include "core/polygon/peters_mis.h"

#include <cmath>

namespace penumbra {
namespace {

double channel_weighted_balance(int j, const TechniqueDensities& pdfs,
                                const std::array<double, kPetersTechniques>& c) {
  double sum = 0;
  for (int k = 0; k < kPetersTechniques; ++k) sum += std::max(0.0, c[k]) * pdfs[k];
  if (!(sum > 0) || !std::isfinite(sum)) return balance_weight(j, pdfs);
  return std::max(0.0, c[j]) * pdfs[j] / sum;
}

}  // namespace

double balance_weight(int j, const TechniqueDensities& pdfs) {
  double sum = 0;
  for (double p : pdfs) sum += p;
  if (!(sum > 0) || !std::isfinite(sum)) return 0;
  return pdfs[j] / sum;
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
                           const UnshadowedIntegrals& unshadowed, double v) {
  double balance = balance_weight(j, pdfs);
  return v * weighted_balance_weight(j, pdfs, unshadowed) +
         (1.0 - v) * Rgb{balance, balance, balance};
}

Rgb peters_mis_weight(PetersHeuristic heuristic, int j, const TechniqueDensities& pdfs,
                      const UnshadowedIntegrals& unshadowed, double v) {
  switch (heuristic) {
    case PetersHeuristic::Balance: {
      double w = balance_weight(j, pdfs);
      return {w, w, w};
    }
    case PetersHeuristic::Weighted:
      return weighted_balance_weight(j, pdfs, unshadowed);
    case PetersHeuristic::ClampedOptimal:
      return clamped_optimal_weight(j, pdfs, unshadowed, v);
  }
  return {0, 0, 0};
}

Rgb combine_psa_ltc(const std::array<std::optional<TechniqueSample>, kPetersTechniques>& samples,
                    const UnshadowedIntegrals& unshadowed, PetersHeuristic heuristic, double v) {
  Rgb estimate{0, 0, 0};
  for (int j = 0; j < kPetersTechniques; ++j) {
    if (!samples[j]) continue;
    const TechniqueSample& s = *samples[j];
    double own_pdf = s.pdfs[j];
    if (!(own_pdf > 0) || !std::isfinite(own_pdf) || !is_finite(s.integrand)) continue;
    Rgb term = peters_mis_weight(heuristic, j, s.pdfs, unshadowed, v) * s.integrand / own_pdf;
    if (is_finite(term)) estimate += term;
  }
  return estimate;
}

}  // namespace penumbra
