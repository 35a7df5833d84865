#pragma once
// Can a method run on a scene? The one check behind the estimator's constructor, a job's
// submission and a batch's validation: every term's strategy must be defined for every light and
// material of the scene, and the combination for the terms and lights.

#include "core/method/method.h"
#include "core/scene/scene.h"

namespace penumbra {

// Throws FormatError (path "method") when a term or combination cannot run on this scene: not
// defined for a light or material of the scene, or a combination of terms it does not define.
// The message quotes the method and names the strategy, the light or material, and why.
void check_method_runs_on(const Scene& scene, const MethodSpec& method);

}  // namespace penumbra
