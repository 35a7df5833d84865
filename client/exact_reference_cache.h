#pragma once
// The client side of `"reference": {"kind": "exact"}` in a batch spec: the exact reference is
// rendered here (core/exact/exact_reference.h, all cores) and uploaded with the batch like an
// EXR reference. It is cached on disk by scene content hash, build flavour and the reference's
// settings, in $PENUMBRA_CACHE_DIR, else $XDG_CACHE_HOME/penumbra, else ~/.cache/penumbra, so a
// second batch on the same scene (the demo run again) reuses it.

#include <filesystem>
#include <string>

#include "core/batch/batch_spec.h"
#include "core/scene/scene.h"

namespace penumbra {

struct CachedExactReference {
  std::string exr;  // the EXR bytes (color, variance of the mean, metadata)
  std::filesystem::path path;
  bool cached = false;              // read from the cache, not rendered now
  double compute_seconds = 0;       // of the render (when rendered now)
  double exact_share = 0;           // of camera samples with the closed form
  double fallback_pixel_share = 0;  // of pixels with a fallback sample (the exact.mask layer)
};

// Renders or reads the exact reference of `scene` for the spec's settings. Throws FormatError
// (fallback method) or std::runtime_error (cache folder not writable).
CachedExactReference exact_reference_for(const Scene& scene, const BatchReferenceSpec& reference);

std::filesystem::path exact_reference_cache_dir();

}  // namespace penumbra
