#pragma once
// BSDF evaluation and sampling for the three materials of SCENE_FORMAT.md. Directions are unit
// vectors pointing away from the surface; `n` is the shading normal, already flipped to the side
// of `wo`. Values are the BSDF f (without the cosine). Below the horizon (dot(n, wi) <= 0) f is 0.

#include <optional>

#include "core/math/vec.h"
#include "core/scene/scene.h"

namespace penumbra {

Rgb eval_bsdf(const Material& material, const Vec3& n, const Vec3& wo, const Vec3& wi);

struct BsdfSample {
  Vec3 wi;
  double pdf_solid_angle = 0;  // density of wi in solid-angle measure (> 0)
};

// Importance-samples wi: cosine for lambert, lobe sampling for phong (diffuse or specular lobe
// chosen by albedo), GGX visible-normal sampling plus cosine for ggx. Empty when it fails
// (e.g. the sampled direction falls below the horizon).
std::optional<BsdfSample> sample_bsdf(const Material& material, const Vec3& n, const Vec3& wo,
                                      const Vec2& u);

// The density sample_bsdf would have produced wi with, in solid-angle measure.
double pdf_bsdf(const Material& material, const Vec3& n, const Vec3& wo, const Vec3& wi);

}  // namespace penumbra
