#pragma once
// The direct-lighting estimator of a method at one shading point: for each light, each term of
// the method draws its samples (stratified by the sampler over the term's count), every sample's
// contribution f * G * V * Le / p is weighted by the method's combination, and the lights' sums
// add up (Salesin & Jarosz Eq. 1-2; Veach's multi-sample MIS with counts n_i).
//
// Combinations: the weights of a sample drawn by term i are the free functions of
// core/method/combination.h (balance, power, avg, the smoothed balance of smooth and
// smooth-fixed with the factor of core/method/smoothing.h, and Peters' weighted and
// clamped-optimal for exactly one psa and one ltc term, per colour channel; weights() reports
// the mean of the three channels' weights for those). Which methods can run on a scene:
// core/method/method_check.h.
//
// Line terms (`line-area`, `line-sa` with direction u or v; core/lines/line_sampling_*.h) need
// the Visibility's line query: their own samples are visible by construction (no shadow ray), and
// their pdf at another term's sample takes one line query through that point, made only for
// visible points with nonzero integrand (one per line direction, shared by the terms along it).

#include <vector>

#include "core/lights/shading_point.h"
#include "core/method/method.h"
#include "core/method/visibility.h"
#include "core/sampling/pattern.h"
#include "core/scene/scene.h"

namespace penumbra {

class DirectLighting {
 public:
  // Throws FormatError (path "method") when the method cannot run on this scene
  // (check_method_runs_on, core/method/method_check.h).
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
