#pragma once
// `line-sa`: Salesin & Jarosz 2019's solid-angle line samples (Sec. 4.1, Eq. 16-19) on a
// rectangular light, built on Ureña et al. 2013's spherical rectangle
// (core/math/spherical_rectangle.h). Ureña's first step picks the line (the arc x = xu), one
// shadow-triangle query finds its visible intervals (clipped at the horizon), their ends map to
// h-intervals, and h is drawn uniformly in the union of the visible h-intervals and mapped back
// to the line. Eq. 19, in solid angle:
//
//   p(l) = (h1 - h0) / (S * sum over visible pieces of (h_hi - h_lo))   (0 if l is hidden),
//
// h0, h1 the h-bounds of the whole line and S the rectangle's solid angle; times
// cos(theta_light) / r^2 in area measure. Unoccluded, it is 1 / S: Ureña's point sampling.
// `v` lines (along edge2) use the rectangle (edge1, edge2); `u` lines the edges swapped.

#include <optional>
#include <string>
#include <string_view>

#include "core/lines/line_sampling_lines.h"
#include "core/math/spherical_rectangle.h"
#include "core/strategies/registry.h"
#include "core/strategies/strategy.h"

namespace penumbra {

class LineSolidAngleStrategy {
 public:
  static constexpr std::string_view name() { return "line-sa"; }
  static constexpr StrategyFamily kFamily = StrategyFamily::Line;
  static constexpr bool kRectangleStrata = false;
  // Rectangular quad lights (supports()), along edge1 (u) or edge2 (v).
  static std::optional<std::string> refusal(const Scene& scene, LineDirection direction);

  // Quads whose edges are perpendicular to 1e-6 relative are rectangles (SCENE_FORMAT.md).
  static bool supports(const Light& light);

  // `query` must outlive the strategy. Lights that are not rectangles: no samples (the
  // estimator refuses them before).
  LineSolidAngleStrategy(const ShadingPoint& sp, const Light& light, LineAxis axis,
                         const LineQuery& query);

  // u.x picks the line (Ureña's u), u.y the h in the visible h-intervals.
  std::optional<LightPoint> sample(const Vec2& u, TracedLine& line, double& t) const;

  // Area density at a point given the family's traced line through it and its t on that line.
  double pdf(const TracedLine& line, double t, const Vec3& light_point) const;
  // The same with its own line query.
  double pdf(const Vec3& light_point) const;

  const std::optional<QuadLineFamily>& family() const { return family_; }

 private:
  double to_area(double pdf_solid_angle, const Vec3& light_point) const;

  const LineQuery* query_;
  std::optional<QuadLineFamily> family_;
  SphericalRectangle rectangle_;
  Vec3 x_, light_normal_;
};

}  // namespace penumbra
