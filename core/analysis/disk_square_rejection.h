#pragma once
// Disk lights sampled as Ramamoorthi et al. 2012 sample them (Sec. 7, footnote 8: "we use
// rejection sampling, with 25 original samples"; Sec. 5.3 and 6: the light's shape multiplies
// the sampling pattern, so a circular light's spectrum, an Airy disk, is convolved with the
// pattern's): the pattern's N points are laid on the disk's bounding square (side 2r, edges
// along the disk's frame), points outside the disk are rejected and contribute zero, and each
// point inside contributes f G V Le / (N p) with p = 1 / (2r)^2 the square's area density. The
// estimate is unbiased for the same integral as the renderer's `area` method, whose disk
// sampling maps the unit square onto the disk with the concentric map instead.
//
// Strata: the square's grid is sqrt(N) x sqrt(N) (aspect 1), so with N = 64 about 50 samples
// land on the disk, as in the paper's Fig. 13 ("50 samples").

#include "core/method/visibility.h"
#include "core/sampling/pattern.h"
#include "core/scene/scene.h"
#include "core/strategies/strategy.h"

namespace penumbra {

// Reflected radiance at sp from every disk light of the scene (other lights are skipped), with
// `samples` points per light drawn by `pattern` from the stream `key` (its `stream` field is
// replaced per light). Finite for finite input; 0 for a point behind or in the plane of a light.
Rgb estimate_disk_lights_by_square_rejection(const Scene& scene, const ShadingPoint& sp,
                                             const Visibility& visibility, Pattern pattern,
                                             const StreamKey& key, int samples);

}  // namespace penumbra
