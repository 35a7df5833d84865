#pragma once
// How many samples per pixel an auto reference needs ("spp": "auto" in a batch spec).
//
// An unbiased estimator's MRSE at N samples per pixel is, in expectation over its noise,
//
//   E[MRSE_N] = mean over pixels and channels of v(p) / (N (mu(p)^2 + eps)) = a / N,
//
// v the per-sample variance (N times the variance of the mean that every EXR's variance layer
// carries) and a = mean v / (mu^2 + eps) the estimator's "noise per sample" over a region
// (core/image/noise_corrected_mrse.h: noise_per_sample measures it from a short probe). The
// reference's own contribution to every error measured against it is the same expression for the
// reference method, a_ref / N_ref (noise_corrected_mrse.h's reference term). Requiring it to be at
// most a share s of the best method's error in a region, a_ref / N_ref <= s min_m (a_m / N_m),
// N_m the spp method m renders at the batch's budget, gives
//
//   N_ref >= a_ref / (s min_m a_m / N_m),
//
// and the reference takes the largest such N over the image and the regions. It is rounded up to
// the quarter-octave grid 2^(k/4) (so that batches with nearly the same need share a cached
// reference), then capped: at most floor(max_seconds / seconds_per_pass) passes, at least 1, at
// most max_spp. The predicted share of the reference in a cell's plain MRSE is then
// r / (1 + r), r = (a_ref / N_ref) / min_m (a_m / N_m), in the region where r is largest.
//
// Pure arithmetic: the probes are rendered and measured by the caller (the coordinator's batch
// manager). Estimates from short probes are themselves noisy, so the prediction is good to the
// probes' accuracy (tens of percent), not exactly.

#include <cstdint>
#include <string>
#include <vector>

namespace penumbra {

struct ReferenceSizingRegion {
  std::string name;              // "image" or a region's name
  double reference_noise = 0;    // a_ref: the reference method's noise per sample
  std::vector<double> expected;  // per method, its expected MRSE at the batch's budget (a_m / N_m)
};

struct ReferenceSizingRequest {
  std::vector<ReferenceSizingRegion> regions;
  double target_share = 0.01;   // s
  double seconds_per_pass = 0;  // of the reference method (compute seconds per pass)
  double max_seconds = 300;     // the cap on the reference's compute seconds
  uint32_t max_spp = 1u << 20;
};

struct ReferenceSizing {
  uint32_t spp = 1;              // what the reference renders
  double required_spp = 0;       // what the target asks for, before rounding and the cap
  bool capped = false;           // the cap (max_seconds or max_spp) bound: spp < required
  double predicted_ratio = 0;    // r at `spp`, in the deciding region
  double predicted_share = 0;    // r / (1 + r)
  double predicted_seconds = 0;  // spp * seconds_per_pass
  std::string deciding_region;   // where r is largest (empty when no region has any error)
  int best_method = -1;          // index of the method with the lowest error there
};

// Throws std::invalid_argument on a negative or non-finite input, a share outside (0, 1), or a
// region whose method list is empty. A region where every method's expected error is 0 is
// skipped (nothing to be a share of); with no region left the reference needs 1 spp.
ReferenceSizing size_reference(const ReferenceSizingRequest& request);

// The smallest 2^(k/4) (k integer >= 0) not below x (x >= 1), as a pass count.
double quarter_octave_ceil(double x);

}  // namespace penumbra
