#pragma once
// Sampling patterns compared in a rendered scene (Ramamoorthi et al. 2012, Figs. 8, 13, 21): the
// error of the direct-lighting estimate with N light samples, at a set of penumbra pixels, for
// each pattern, with many independent trials per pixel.
//
// Pixels. The shading point of a pixel is the first hit of the ray through its centre (no pixel
// jitter, as in the probe, so only the light samples vary). Candidate pixels on a grid of
// `pixel_stride` over a region are screened with a stratified estimate of their visible fraction
// (the estimate over the estimate without occluders); those in
// [min_visible_fraction, max_visible_fraction] are in the penumbra, and at most `max_pixels` of
// them, evenly spread over the candidates' order, are measured.
//
// Error. Every pixel's reference is the mean of `reference_trials` stratified estimates with
// `reference_samples` samples. Pattern P's squared error at pixel p is the mean over `trials`
// estimates e_t of (e_t - reference_p)^2 (the channel mean of the RGB estimate): bias and variance
// together, as the paper's "numerical error" (the uniform pattern has no randomness, so its error
// is all bias, and one trial measures it). The relative RMS error of a pattern over the pixels is
// sqrt(sum_p error_p / sum_p reference_p^2).
//
// Pixels and trials. The comparisons of the suite are means over pixels of per-pixel errors, whose
// spread comes mostly from pixel to pixel (how many discontinuities, where): many pixels with a
// few dozen trials each resolve them better than few pixels with many trials.
//
// Deterministic: the trials of pattern P at N use streams keyed by (seed, N, P; pixel; trial),
// and the result does not depend on the number of threads.

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/sampling/pattern.h"
#include "core/scene/scene.h"

namespace penumbra {

// How the studied estimates draw points on disk lights (the references always use `method`).
enum class DiskSampling {
  Method,           // the method's strategy (`area`: the concentric map of the unit square)
  SquareRejection,  // the paper's: rejection from the bounding square (disk_square_rejection.h)
};

struct PatternErrorOptions {
  std::string method = "area";  // the paper samples the light's area (its samples are light points)
  DiskSampling disk_sampling = DiskSampling::Method;  // SquareRejection: every light a disk
  int samples = 16;                                   // N light samples per estimate
  int trials = 32;                                    // independent estimates per pixel and pattern
  std::string region;    // a region of the scene; empty: the whole image
  int pixel_stride = 4;  // candidates every `pixel_stride` pixels in x and y
  int max_pixels = 1000;
  double min_visible_fraction = 0.05, max_visible_fraction = 0.95;
  int screening_samples = 64;
  int reference_samples = 4096;
  int reference_trials = 1;
  uint64_t seed = 2012;
  int threads = 0;  // 0: the hardware's count
};

struct PatternErrorResult {
  Pattern pattern = Pattern::Stratified;
  std::vector<double> pixel_squared_error;  // per measured pixel, in the study's pixel order
  double mean_squared_error = 0;            // mean over the pixels
  double relative_rms_error = 0;            // sqrt(sum error / sum reference^2)
  double seconds = 0;                       // wall time of this pattern's trials
};

struct PatternErrorStudy {
  std::string scene;
  PatternErrorOptions options;
  int candidate_pixels = 0;                  // screened
  std::vector<std::pair<int, int>> pixels;   // measured (x, y)
  std::vector<double> reference;             // per pixel (channel mean)
  std::vector<double> visible_fraction;      // per pixel, from the screening
  std::vector<PatternErrorResult> patterns;  // in the order asked

  const PatternErrorResult& result(Pattern pattern) const;  // throws std::out_of_range
};

// The penumbra pixels of a region, screened as described above (at most options.max_pixels of
// them), with their visible fractions. Throws as measure_pattern_errors.
struct PenumbraPixels {
  int candidates = 0;
  std::vector<std::pair<int, int>> pixels;
  std::vector<double> visible_fraction;
};
PenumbraPixels find_penumbra_pixels(std::shared_ptr<const Scene> scene,
                                    const PatternErrorOptions& options);

// Throws FormatError for a method that cannot run on the scene or an unknown region, and
// std::invalid_argument for options out of range or when no pixel of the region is in the
// penumbra.
PatternErrorStudy measure_pattern_errors(std::shared_ptr<const Scene> scene,
                                         const std::vector<Pattern>& patterns,
                                         const PatternErrorOptions& options);

// The same study at several N (options.samples is ignored): the pixels and their references
// are found once and shared; each N draws its own independent trials. One study per N, in order.
std::vector<PatternErrorStudy> measure_pattern_error_sweep(std::shared_ptr<const Scene> scene,
                                                           const std::vector<Pattern>& patterns,
                                                           const std::vector<int>& sample_counts,
                                                           const PatternErrorOptions& options);

}  // namespace penumbra
