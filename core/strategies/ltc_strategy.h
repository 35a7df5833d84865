#pragma once
// `ltc`: sampling a quad or polygon light proportional to a linearly transformed cosine fitted
// to the shading point's specular lobe (Peters 2021, Sec. 4.1; LTCs: Heitz et al. 2016), as a
// point strategy (core/strategies/strategy.h).
//
// The polygon's vertices, in the shading frame whose x-axis is wo's tangential direction, are
// mapped by M^-1, sampled with projected solid angle sampling (ProjectedSolidAngleSampler, which
// clips at z = 0 in the cosine space), and the direction mapped back by M and normalized. The
// density per unit solid angle is p_M(w) / I with I = integral over the light of p_M (Peters
// Eq. 10: the transformed polygon's projected solid angle over pi); per unit AREA
//   p_area = p_M(w) / I * cos(theta_light) / r^2.
// As Peters does, we clip only in the cosine space: a sample may fall below the shading point's
// horizon (the integrand is 0 there); pdf() is consistent with that.
//
// Materials: `ggx` uses the fitted table (core/materials/ltc_ggx_table.h, alpha = roughness clamped
// like the BSDF does, theta_o from wo and the normal). `lambert` uses the identity (a clamped
// cosine): then ltc == psa. `phong` is not fitted: it also gets the identity (ltc == psa), an
// unbiased but uninformed choice, and its lobe albedo is reported as 0 so that Peters' weighted
// heuristic gives this strategy no weight. The light emits on one side: a shading point behind
// it (or on its plane) gets no samples. Disks are refused (std::invalid_argument).

#include <optional>
#include <string>
#include <string_view>

#include "core/lights/polygon_light.h"
#include "core/math/ltc_distribution.h"
#include "core/math/projected_solid_angle.h"
#include "core/math/vec.h"
#include "core/scene/scene.h"
#include "core/strategies/light_checks.h"
#include "core/strategies/registry.h"
#include "core/strategies/strategy.h"

namespace penumbra {

// The LTC standing for the material's non-diffuse lobe at a view cosine, and that lobe's albedo
// per channel (ggx: F0 albedo + (1 - F0) fresnel from the table; 0 for lambert, phong, null).
struct MaterialLtc {
  LinearlyTransformedCosine ltc;
  Rgb lobe_albedo{0, 0, 0};
};
MaterialLtc material_ltc(const Material* material, double cos_theta_o);

// The shading frame the table's LTCs live in: z = normal, x = wo's direction in the tangent
// plane (any tangent when wo is along the normal).
Frame ltc_shading_frame(const Vec3& normal, const Vec3& wo);

class LtcStrategy {
 public:
  LtcStrategy(const ShadingPoint& sp, const Light& light,
              int iterations = ProjectedSolidAngleSampler::kDefaultIterations);

  static constexpr std::string_view name() { return "ltc"; }
  static constexpr StrategyFamily kFamily = StrategyFamily::Point;
  static constexpr bool kRectangleStrata = false;
  // Quads and convex polygons of up to kMaxPolygonVertices vertices (not disks).
  static std::optional<std::string> refusal(const Scene& scene, LineDirection) {
    return polygon_lights_only(name(), scene);
  }
  // Empty: nothing of the light in the LTC's support, behind the light, or degenerate.
  std::optional<LightPoint> sample(const Vec2& u) const;
  // Area density at a point on the light; 0 outside the polygon, behind it, or where p_M = 0.
  double pdf(const Vec3& light_point) const;

  // Integral of p_M over the light (Peters Eq. 10), in [0, 1].
  double ltc_integral() const { return sampler_.projected_solid_angle() * kInvPi; }
  // The albedo of the lobe the LTC approximates (Peters' a_1), per channel.
  const Rgb& lobe_albedo() const { return lobe_albedo_; }
  const LinearlyTransformedCosine& ltc() const { return ltc_; }

 private:
  LtcStrategy(const ShadingPoint& sp, const Light& light, const MaterialLtc& fitted,
              int iterations);
  static ProjectedSolidAngleSampler make_sampler(const Vec3& position, const Frame& frame,
                                                 const PolygonLightGeometry& geometry,
                                                 const LinearlyTransformedCosine& ltc,
                                                 int iterations);

  Vec3 position_;
  Frame frame_;
  PolygonLightGeometry geometry_;
  LinearlyTransformedCosine ltc_;
  Rgb lobe_albedo_;
  ProjectedSolidAngleSampler sampler_;  // of the polygon transformed by M^-1
};

}  // namespace penumbra
