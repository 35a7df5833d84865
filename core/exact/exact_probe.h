#pragma once
// `penumbra exact SCENE PROBE`: the exact reflected radiance at a probe's pixels and points
// (penumbra/probe@1, SCENE_FORMAT.md), where the closed form applies, else the fallback estimate:
//   {"format": "penumbra/exact-result@1", "fallback": {"method": ..., "samples": ...},
//    "points": [{"index": i, "radiance": [r, g, b], "exact": true}, ...],
//    "exact_share": 0.75, "fallback_points": 2}
// pixels first, then points, in input order (as penumbra/probe-result@1 numbers them).

#include <memory>
#include <string>

#include "core/exact/exact_shading.h"
#include "core/render/probe.h"

namespace penumbra {

// Throws FormatError for a pixel outside the image, an unknown material or a fallback method
// that cannot run on the scene.
std::string exact_probe_json(std::shared_ptr<const Scene> scene, const ProbeSpec& probe,
                             const ExactShadingOptions& options = {}, uint64_t seed = 0x5eed);

}  // namespace penumbra
