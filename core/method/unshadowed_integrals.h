#pragma once
// Peters 2021, Sec. 4.2: the unshadowed integrals c_j of a polygon light at a shading point,
// the coefficients of the weighted balance heuristic (core/method/combination.h):
//   c_0 = L_e max(a_0, 0.01) PSA / pi        (diffuse: the identity LTC, Lambert's form factor)
//   c_1 = L_e a_1 integral_P p_M             (specular: the LTC's integral, Peters Eq. 10)
// per colour channel. a_0 is the diffuse albedo (lambert: albedo, phong: kd, ggx: diffuse),
// clamped to at least 0.01 per channel as Peters advises (only p_0 covers the whole polygon above
// the horizon); a_1 the specular lobe's albedo (LtcStrategy::lobe_albedo()). L_e is the light's
// radiance (for a gaussian profile its peak: the c_j only steer weights, any value is unbiased).
// These are also the classic LTC estimate of unshadowed shading (Heitz et al. 2016).

#include "core/lights/shading_point.h"
#include "core/method/combination.h"
#include "core/scene/scene.h"
#include "core/strategies/ltc_strategy.h"
#include "core/strategies/psa_strategy.h"

namespace penumbra {

inline constexpr double kMinDiffuseAlbedoForWeights = 0.01;

// The diffuse albedo a_0 of a material (0 for none).
Rgb diffuse_albedo(const Material* material);

// {c_0, c_1} for the prepared psa and ltc strategies of one shading point and light.
UnshadowedIntegrals unshadowed_polygon_shading(const ShadingPoint& sp, const Light& light,
                                               const ProjectedSolidAngleStrategy& psa,
                                               const LtcStrategy& ltc);

}  // namespace penumbra
