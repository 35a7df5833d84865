#pragma once
// `bsdf`: BSDF importance sampling (core/materials/bsdf.h) of a direction, traced to the light.
// A direction that misses the light is no sample. The solid-angle density converts to area
// measure as p_area = p_sa |cos(theta_light)| / r^2, and pdf() converts the same way.
//
// Like the other point strategies, it gives no sample (and density 0) when the shading point is
// not strictly in front of the light (light_faces_point): the light sends it nothing, and all
// strategies agree on where the integrand is zero.

#include <optional>
#include <string>
#include <string_view>

#include "core/strategies/registry.h"
#include "core/strategies/strategy.h"

namespace penumbra {

class BsdfStrategy {
 public:
  // The strategy's name in the method grammar (SCENE_FORMAT.md).
  static constexpr std::string_view name() { return "bsdf"; }
  static constexpr StrategyFamily kFamily = StrategyFamily::Point;
  static constexpr bool kRectangleStrata = false;
  // Runs on every light and material.
  static std::optional<std::string> refusal(const Scene&, LineDirection) { return std::nullopt; }

  BsdfStrategy(const ShadingPoint& sp, const Light& light);
  std::optional<LightPoint> sample(const Vec2& u) const;
  // Area density at a point of the light.
  double pdf(const Vec3& light_point) const;

 private:
  ShadingPoint sp_;
  const Light* light_;
  bool active_ = false;  // a material and a light that faces the point
};

}  // namespace penumbra
