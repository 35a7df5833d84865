#pragma once
// `area`: uniform sampling of the light's surface (SCENE_FORMAT.md). Quads: the parallelogram
// map; polygons: a triangle of the fan around vertex 0 chosen by area, then the square-root map;
// disks: the concentric map. Density 1 / area in area measure.
//
// A shading point that is not strictly in front of the light (on its plane or behind it: the
// light sends it nothing) gets no sample, and the density is 0 there.

#include <optional>
#include <string>
#include <string_view>

#include "core/strategies/registry.h"
#include "core/strategies/strategy.h"

namespace penumbra {

class AreaStrategy {
 public:
  // The strategy's name in the method grammar (SCENE_FORMAT.md).
  static constexpr std::string_view name() { return "area"; }
  static constexpr StrategyFamily kFamily = StrategyFamily::Point;
  static constexpr bool kRectangleStrata = true;
  // Runs on every light and material.
  static std::optional<std::string> refusal(const Scene&, LineDirection) { return std::nullopt; }

  AreaStrategy(const ShadingPoint& sp, const Light& light);
  std::optional<LightPoint> sample(const Vec2& u) const;
  // Area density at a point of the light (the point is assumed to lie on the light).
  double pdf(const Vec3& light_point) const;

 private:
  const Light* light_;
  double pdf_area_ = 0;  // 1 / area, or 0 when the strategy cannot sample
};

}  // namespace penumbra
