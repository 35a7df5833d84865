#pragma once
// `bsdf`: BSDF importance sampling (core/materials/bsdf.h) of a direction, traced to the light
// (either side of it: the back side simply emits nothing). A direction that misses the light is
// no sample. The solid-angle density converts to area measure as
// p_area = p_sa |cos(theta_light)| / r^2, and pdf() converts the same way for any point.

#include <optional>

#include "core/strategies/strategy.h"

namespace penumbra {

class BsdfStrategy {
 public:
  BsdfStrategy(const ShadingPoint& sp, const Light& light);
  std::optional<LightPoint> sample(const Vec2& u) const;
  // Area density at a point of the light.
  double pdf(const Vec3& light_point) const;

 private:
  ShadingPoint sp_;
  const Light* light_;
};

}  // namespace penumbra
