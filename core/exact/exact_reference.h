#pragma once
// A reference image whose only noise, where the closed form applies, is the camera-sample
// (antialiasing) average: per pixel, `camera_samples` jittered camera rays (stratified over a
// grid when the count is a square), each shaded exactly
// (core/exact/exact_shading.h) or, on materials and lights without a closed form, by the fallback
// method with many samples. The film carries the mean and the variance of the mean per pixel (as
// every render does), so the report accounts for the remaining noise; `exact_fraction` says per
// pixel which share of its camera samples was exact (1: exact up to antialiasing; 0: fallback).

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/exact/exact_shading.h"
#include "core/image/image.h"
#include "core/render/film.h"

namespace penumbra {

struct ExactReferenceOptions {
  ExactShadingOptions shading;
  uint32_t camera_samples = 16;  // jittered camera rays per pixel
  uint64_t seed = 0x5eed;
  int threads = 0;  // 0: all
};

// The EXR channel of an exact reference that marks where the closed form did not apply: per
// pixel, the share of its camera samples shaded by the fallback (0: exact up to antialiasing, 1:
// every sample a converged estimate).
inline constexpr const char* kExactMaskChannel = "exact.mask";

struct ExactReferenceImage {
  Film film;
  Image exact_fraction;  // per pixel, in all three channels
  // The exact.mask channel: 1 - exact_fraction per pixel.
  std::vector<float> fallback_mask() const;
  // Share of the pixels with any fallback sample (mask > 0).
  double fallback_pixel_share() const;
  uint64_t exact_samples = 0, fallback_samples = 0;
  VisibleLightStats stats;
  double compute_seconds = 0, wall_seconds = 0;
};

// Throws FormatError when the fallback method cannot run on the scene.
ExactReferenceImage render_exact_reference(std::shared_ptr<const Scene> scene,
                                           const ExactReferenceOptions& options = {});

// EXR metadata of an exact reference ("penumbra:method" = "exact", the fallback, counts, the
// shares of exact camera samples and of pixels with a fallback sample).
ImageMetadata exact_reference_metadata(const Scene& scene, const ExactReferenceOptions& options,
                                       const ExactReferenceImage& image);

// The EXR of an exact reference: color, variance of the mean, the exact.mask channel and
// `metadata`.
std::string encode_exact_reference(const ExactReferenceImage& image, const ImageMetadata& metadata);

}  // namespace penumbra
