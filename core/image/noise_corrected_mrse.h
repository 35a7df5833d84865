#pragma once
// MRSE with the reference's own noise accounted for.
//
// A reference rendered by Monte Carlo is itself noisy, and its noise enters every error measured
// against it: at a short reference the reported MRSE is mostly the reference's. Each pixel
// channel of the reference is R = mu + e, mu the true value, e its error with E[e] = 0 and
// Var[e] = sigma^2, the variance of the mean that the reference EXR carries (its variance
// layer, s^2, an unbiased estimate: E[s^2] = sigma^2). The test image I is independent of R.
// What we want is the test's own error against the truth, T = (I - mu)^2 / (mu^2 + eps); what
// we measure is Q = (I - R)^2 / (R^2 + eps) (Salesin & Jarosz's MRSE, eps = 1e-6). With
// d = I - mu and g(r) = 1 / (r^2 + eps), (I - R)^2 = d^2 - 2 d e + e^2, and over the
// reference's noise
//
//   E[Q] = E[(d^2 - 2 d e + e^2) g(mu + e)]
//        = d^2 g(mu) + sigma^2 g(mu)             (numerator: the reference adds sigma^2)
//          - 2 d g'(mu) sigma^2 + d^2 g''(mu) sigma^2 / 2 + g'(mu) E[e^3] + O(sigma^4).
//
// The reference-noise term is sigma^2 g(mu), estimated per pixel channel by s^2 g(R); the
// corrected error is
//
//   C = mean over pixels and channels of [(I - R)^2 - s^2] / (R^2 + eps)
//     = plain MRSE - mean of s^2 / (R^2 + eps).
//
// Its bias: E[s^2 g(R)] = sigma^2 g(mu) + g'(mu) Cov(s^2, e) + ..., and for a mean of n samples
// Cov(s^2, e) = mu_3 / n^2 = E[e^3], so the reference's skewness (large in penumbrae, where few of
// its samples see the light) cancels between Q and the correction at this order. The -2 d g'
// sigma^2 term has the sign of d and averages out over pixels of an unbiased test. What remains
// is relative, of order 3 sigma^2 / mu^2 (g''/(2 g) = (3 mu^2 - eps) / (mu^2 + eps)^2), the
// square of the reference's relative standard error per pixel: 0.3% for a reference with 3%
// relative noise. C can come out below zero (slightly) when the test is far cleaner than the
// reference; the reference's share (below) says when that happens.
//
// The reference's share of a cell's error is mean(s^2 g(R)) / plain: the part of the plain MRSE
// that is the reference's noise, not the method's.
//
// The reference's realised error is common to every run measured against it, so it does not
// average out over repeats: reference_deviation is the standard deviation of C that it causes,
// from Var[(e^2 - s^2) g] ~ 2 sigma^4 g^2 per channel (gaussian e, s^2 from many samples), the
// three channels of a pixel taken as fully correlated (they share the pixel's samples) and
// pixels as independent. Paired comparisons of two methods against the same reference do not
// see it: it is the same number in both.

#include <cstdint>
#include <map>
#include <string>

#include "core/image/image.h"
#include "core/image/metrics.h"
#include "core/scene/scene.h"

namespace penumbra {

struct NoiseCorrectedError {
  double plain = 0;           // MRSE against the reference, mean of (I - R)^2 / (R^2 + eps)
  double reference_term = 0;  // mean of s^2 / (R^2 + eps): the reference's expected contribution
  double corrected = 0;       // plain - reference_term
  double reference_deviation = 0;  // standard deviation of `corrected` from the reference's noise
  bool has_variance = false;       // the reference carried a variance layer

  // reference_term / plain: the share of the plain MRSE that is the reference's noise (0 when
  // plain is 0; can exceed 1 when the test is cleaner than the reference).
  double reference_share() const;
};

// Over a region (clipped to the image) or the whole image. `reference_variance` is the
// reference's variance of the mean per channel (its EXR's variance layer); an empty (0x0) image
// means it has none: then reference_term and reference_deviation are 0 and has_variance false.
// Throws std::invalid_argument on size mismatch, an empty region, or a variance that is negative
// or not finite (naming the pixel).
NoiseCorrectedError noise_corrected_mrse(const Image& test, const Image& reference,
                                         const Image& reference_variance, const Region& region,
                                         double epsilon = kMrseEpsilon);
NoiseCorrectedError noise_corrected_mrse(const Image& test, const Image& reference,
                                         const Image& reference_variance,
                                         double epsilon = kMrseEpsilon);

// "image" for the whole image, then one entry per region (errors name the region).
std::map<std::string, NoiseCorrectedError> noise_corrected_summary(
    const Image& test, const Image& reference, const Image& reference_variance,
    const std::map<std::string, Region>& regions);

// The reference's own expected MRSE against the truth, mean of s^2 / (R^2 + eps) over the
// region: what `reference_term` is for any test image. Used to size a reference.
double reference_noise_mrse(const Image& reference, const Image& reference_variance,
                            const Region& region, double epsilon = kMrseEpsilon);

// An estimator's noise per sample over the region: mean over pixels and channels of
// spp * variance(p) / (denominator(p)^2 + eps), `variance` its EXR's variance of the mean at
// `spp` samples per pixel and `denominator` an estimate of the true image (the same for every
// estimator compared, so that their ratios do not depend on its noise). Its expected MRSE at N
// samples per pixel is this over N (core/batch/reference_sizing.h). Throws
// std::invalid_argument like noise_corrected_mrse.
double noise_per_sample(const Image& variance, uint32_t spp, const Image& denominator,
                        const Region& region, double epsilon = kMrseEpsilon);

}  // namespace penumbra
