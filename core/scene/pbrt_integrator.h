#pragma once
// pbrt-v3 Integrator statements onto Penumbra's method grammar (`penumbra/method@1`):
// the seed implementation's `pointline` integrator (Salesin & Jarosz 2019), pbrt-v3's
// `directlighting`, and a direct-lighting default for `path` and `whitted`. The mapping table is
// in the README ("pbrt-v3 scenes").

#include <string>
#include <vector>

#include "core/scene/pbrt_params.h"
#include "core/scene/scene.h"

namespace penumbra {

// Fills `defaults` (method, seconds) and `max_depth` (pbrt-v3's maxdepth, Scene::max_depth)
// from an Integrator statement. `light_samples` is
// the area lights' sample count (xsamples * ysamples of AreaLightSource; pbrt-v3's "samples").
// Adds a warning for every setting mapped approximately; throws FormatError for settings that
// have no Penumbra counterpart (e.g. a surface-area line at an angle that is not along an edge).
void map_pbrt_integrator(PbrtParams& params, int light_samples, SceneRenderDefaults& defaults,
                         int& max_depth, std::vector<std::string>& warnings);

}  // namespace penumbra
