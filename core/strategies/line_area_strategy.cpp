#include "core/strategies/line_area_strategy.h"

#include <algorithm>
#include <cmath>

#include "core/strategies/light_checks.h"

namespace penumbra {

namespace {

// t at the fraction `target` of the total length of the visible pieces.
double t_at_visible_fraction(const IntervalList& visible, double target) {
  for (const Interval& piece : visible) {
    if (target <= piece.length()) return std::clamp(piece.lo + target, piece.lo, piece.hi);
    target -= piece.length();
  }
  return visible.highest();
}

}  // namespace

LineAreaStrategy::LineAreaStrategy(const ShadingPoint& sp, const Light& light, LineAxis axis,
                                   const LineQuery& query)
    : query_(&query) {
  if (light.type != LightType::Quad) return;
  // Only a shading point strictly in front of the emitting side receives light.
  if (!(dot(light.normal, sp.position - light.origin) > 0)) return;
  family_ = QuadLineFamily::prepare(sp.position, sp.normal, light, axis);
  area_ = light.area;
  if (!(area_ > 0)) family_.reset();
}

std::optional<LightPoint> LineAreaStrategy::sample(const Vec2& u, TracedLine& line,
                                                   double& t) const {
  if (!family_) return std::nullopt;
  double offset = std::clamp(u.x, 0.0, 1.0);
  family_->trace(offset, *query_, line);
  if (line.visible.empty()) return std::nullopt;
  double visible = line.visible.visible_length();
  if (!(visible > 0)) return std::nullopt;
  t = t_at_visible_fraction(line.visible, std::clamp(u.y, 0.0, 1.0) * visible);
  LightPoint point;
  point.position = family_->point_at(offset, t);
  point.pdf_area = 1.0 / (area_ * visible);
  if (!std::isfinite(point.pdf_area)) return std::nullopt;
  return point;
}

double LineAreaStrategy::pdf(const TracedLine& line, double t) const {
  if (!family_ || visible_piece_containing(line, t) < 0) return 0;
  double visible = line.visible.visible_length();
  if (!(visible > 0)) return 0;
  double pdf = 1.0 / (area_ * visible);
  return std::isfinite(pdf) ? pdf : 0.0;
}

double LineAreaStrategy::pdf(const Vec3& light_point) const {
  if (!family_) return 0;
  Vec2 st = family_->coordinates(light_point);
  if (!(st.x >= 0 && st.x <= 1 && st.y >= 0 && st.y <= 1)) return 0;
  TracedLine line;
  family_->trace(st.x, *query_, line);
  return pdf(line, st.y);
}

}  // namespace penumbra

namespace penumbra {

std::optional<std::string> LineAreaStrategy::refusal(const Scene& scene, LineDirection direction) {
  if (auto why = edge_direction_only(name(), direction)) return why;
  return first_light_not_quad(scene,
                              "strategy \"line-area\" samples lines of quad lights (along "
                              "edge1 or edge2)");
}

}  // namespace penumbra
