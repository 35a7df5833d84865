#pragma once
// The direct-lighting estimator of a method at one shading point: for each light, each term of
// the method draws its samples (stratified by the sampler over the term's count), every sample's
// contribution f * G * V * Le / p is weighted by the method's combination, and the lights' sums
// add up (Salesin & Jarosz Eq. 1-2; Veach's multi-sample MIS with counts n_i).
//
// Combinations (weights of a sample x drawn by term i; n_k = count of term k, p_k its area pdf):
//   balance  w_i = n_i p_i / sum_k n_k p_k
//   power    w_i = (n_i p_i)^2 / sum_k (n_k p_k)^2            (Veach's beta = 2)
//   avg      w_i = 1 / T                                        (plain average of the T estimates)
//   smooth-fixed, smooth: balance with the BSDF terms' pdfs eased to 0 at the light's edges
//            (and, for smooth, at occluder edges found by the method's line terms): Salesin &
//            Jarosz Eq. 22-24, core/method/smoothing.h. Quad lights only.
//   weighted, clamped-optimal: Peters 2021 Sec. 4.2-4.3 for exactly one psa and one ltc term
//            (`psa+ltc/weighted`, `2*psa+ltc/clamped-optimal`; polygon and quad lights): per
//            colour channel w_j = c_j p_j / sum_k c_k p_k with c_j the unshadowed integrals of
//            the shading point and light (core/polygon/ltc_unshadowed_shading.h), and its blend
//            with balance (v = 1/2); core/polygon/peters_mis.h. weights() reports the mean of
//            the three channels' weights.
//
// Line terms (`line-area`, `line-sa` with direction u or v; core/lines/line_sampling_*.h) need
// the Visibility's line query: their own samples are visible by construction (no shadow ray), and
// their pdf at another term's sample takes one line query through that point, made only for
// visible points with nonzero integrand (one per line direction, shared by the terms along it).

#include <vector>

#include "core/method/method.h"
#include "core/method/visibility.h"
#include "core/sampling/pattern.h"
#include "core/scene/scene.h"
#include "core/strategies/strategy.h"

namespace penumbra {

class DirectLighting {
 public:
  // Throws FormatError (path "method") when a term or combination cannot run on this scene:
  // not available yet, or not defined for a light or material of the scene (the message names
  // the strategy, the light or material, and why).
  DirectLighting(const Scene& scene, const MethodSpec& method);

  // Reflected radiance towards sp.wo. `key` identifies the shading point's random streams (its
  // `stream` field is ignored: streams are assigned per light and term). Every term draws
  // count * sample_multiplier samples (the probe's N).
  Rgb estimate(const ShadingPoint& sp, const Visibility& visibility, Pattern pattern,
               const StreamKey& key, int sample_multiplier = 1) const;

  // The combination weights of a point on `light_index` drawn by `term`, for tests: the weights
  // of all terms at the same point sum to one wherever some pdf is nonzero.
  // Line terms need `lines` (the scene's line query); their pdf is 0 at hidden points.
  std::vector<double> weights(const ShadingPoint& sp, int light_index, const Vec3& light_point,
                              int sample_multiplier = 1, const LineQuery* lines = nullptr) const;

  // Does the method have line terms (so the Visibility must provide a line query)?
  bool needs_line_query() const;

  const MethodSpec& method() const { return method_; }

 private:
  const Scene* scene_;
  MethodSpec method_;
};

// Stream numbers: 0 is the pixel jitter; each (light, term) pair gets its own.
inline constexpr uint32_t kPixelJitterStream = 0;
inline uint32_t light_term_stream(int light_index, int term_index) {
  return 1 + uint32_t(light_index) * 32 + uint32_t(term_index);
}

}  // namespace penumbra
