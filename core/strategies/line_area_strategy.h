#pragma once
// `line-area`: Salesin & Jarosz 2019's surface-area line samples (Sec. 4.1, Eq. 14-15) on a
// parallelogram light. The line's offset is uniform across the light (every line of a
// parallelogram along one edge has the same length, so Eq. 14's p(v) = length / area is uniform),
// one shadow-triangle query finds its visible intervals (clipped at the shading point's
// horizon), and the point is uniform in them. In area measure:
//
//   p(l) = p(v) p(u|v) = 1 / (area * visible fraction of the line through l)   (0 if l is hidden)
//
// A line sample's point is visible by construction (no shadow ray). A fully occluded line gives
// no sample: it contributes 0, which is its exact integral.

#include <optional>
#include <string>
#include <string_view>

#include "core/lines/line_sampling_lines.h"
#include "core/strategies/registry.h"
#include "core/strategies/strategy.h"

namespace penumbra {

class LineAreaStrategy {
 public:
  static constexpr std::string_view name() { return "line-area"; }
  static constexpr StrategyFamily kFamily = StrategyFamily::Line;
  static constexpr bool kRectangleStrata = false;
  // Quad lights, along edge1 (u) or edge2 (v).
  static std::optional<std::string> refusal(const Scene& scene, LineDirection direction);

  // `query` must outlive the strategy. Lights other than quads: no samples (the estimator
  // refuses them before).
  LineAreaStrategy(const ShadingPoint& sp, const Light& light, LineAxis axis,
                   const LineQuery& query);

  // u.x picks the line (the dimension to stratify), u.y the point in its visible intervals.
  // `line` receives the traced line and `t` where the point lies on it.
  std::optional<LightPoint> sample(const Vec2& u, TracedLine& line, double& t) const;

  // Area density at a point of the light, given the traced line through it (the family's line at
  // the point's offset) and the point's t on that line.
  double pdf(const TracedLine& line, double t) const;
  // The Line family's entry point (the point itself is not needed).
  double pdf(const TracedLine& line, double t, const Vec3&) const { return pdf(line, t); }
  // The same with its own line query.
  double pdf(const Vec3& light_point) const;

  const std::optional<QuadLineFamily>& family() const { return family_; }

 private:
  const LineQuery* query_;
  std::optional<QuadLineFamily> family_;
  double area_ = 0;
};

}  // namespace penumbra
