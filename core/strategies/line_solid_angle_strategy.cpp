#include "core/strategies/line_solid_angle_strategy.h"

#include <algorithm>
#include <cmath>

#include "core/strategies/light_checks.h"

namespace penumbra {

namespace {

struct HIntervals {
  double line_length = 0;     // h1 - h0 of the whole line
  double visible_length = 0;  // sum of the visible pieces' h-lengths
};

// h of the point at t on the line x = xu.
double h_at(const SphericalRectangle& r, double d, double t) {
  return SphericalRectangle::h_of_y(d, r.y_at_fraction(t));
}

HIntervals h_intervals(const SphericalRectangle& r, const SphericalRectangle::HBounds& bounds,
                       const IntervalList& visible) {
  HIntervals h;
  h.line_length = bounds.h1 - bounds.h0;
  for (const Interval& piece : visible)
    h.visible_length += std::max(0.0, h_at(r, bounds.d, piece.hi) - h_at(r, bounds.d, piece.lo));
  return h;
}

}  // namespace

bool LineSolidAngleStrategy::supports(const Light& light) {
  return light.type == LightType::Quad && std::abs(dot(light.edge1, light.edge2)) <=
                                              1e-6 * length(light.edge1) * length(light.edge2);
}

LineSolidAngleStrategy::LineSolidAngleStrategy(const ShadingPoint& sp, const Light& light,
                                               LineAxis axis, const LineQuery& query)
    : query_(&query), x_(sp.position), light_normal_(light.normal) {
  if (!supports(light)) return;
  if (!(dot(light.normal, sp.position - light.origin) > 0)) return;
  // The spherical rectangle's lines x = xu run along its second edge.
  const Vec3& across = axis == LineAxis::Edge1 ? light.edge2 : light.edge1;
  const Vec3& along = axis == LineAxis::Edge1 ? light.edge1 : light.edge2;
  auto rectangle = SphericalRectangle::prepare(sp.position, light.origin, across, along);
  if (!rectangle) return;
  rectangle_ = *rectangle;
  family_ = QuadLineFamily::prepare(sp.position, sp.normal, light, axis);
}

double LineSolidAngleStrategy::to_area(double pdf_solid_angle, const Vec3& light_point) const {
  Vec3 d = light_point - x_;
  double r2 = length_squared(d);
  if (!(r2 > 0)) return 0;
  double cos_light = std::abs(dot(light_normal_, d)) / std::sqrt(r2);
  double pdf = pdf_solid_angle * cos_light / r2;
  return std::isfinite(pdf) ? pdf : 0.0;
}

std::optional<LightPoint> LineSolidAngleStrategy::sample(const Vec2& u, TracedLine& line,
                                                         double& t) const {
  if (!family_) return std::nullopt;
  const SphericalRectangle& r = rectangle_;
  double xu = r.line_x(std::clamp(u.x, 0.0, 1.0));
  double offset = std::clamp((xu - r.x0) / (r.x1 - r.x0), 0.0, 1.0);
  family_->trace(offset, *query_, line);
  if (line.visible.empty()) return std::nullopt;
  SphericalRectangle::HBounds bounds = r.h_bounds(xu);
  HIntervals h = h_intervals(r, bounds, line.visible);
  if (!(h.visible_length > 0) || !(h.line_length > 0)) return std::nullopt;

  // h uniform in the union of the visible h-intervals.
  double target = std::clamp(u.y, 0.0, 1.0) * h.visible_length;
  t = line.visible.highest();
  for (const Interval& piece : line.visible) {
    double h_lo = h_at(r, bounds.d, piece.lo), h_hi = h_at(r, bounds.d, piece.hi);
    double piece_h = std::max(0.0, h_hi - h_lo);
    if (target <= piece_h) {
      double y = r.y_of_h(bounds.d, h_lo + target);
      t = std::clamp((y - r.y0) / (r.y1 - r.y0), piece.lo, piece.hi);
      break;
    }
    target -= piece_h;
  }
  LightPoint point;
  point.position = family_->point_at(offset, t);
  point.pdf_area =
      to_area(r.line_sample_solid_angle_pdf(h.line_length, h.visible_length), point.position);
  if (!(point.pdf_area > 0)) return std::nullopt;
  return point;
}

double LineSolidAngleStrategy::pdf(const TracedLine& line, double t,
                                   const Vec3& light_point) const {
  if (!family_ || visible_piece_containing(line, t) < 0) return 0;
  const SphericalRectangle& r = rectangle_;
  double xu = r.x0 + line.offset * (r.x1 - r.x0);
  SphericalRectangle::HBounds bounds = r.h_bounds(xu);
  HIntervals h = h_intervals(r, bounds, line.visible);
  return to_area(r.line_sample_solid_angle_pdf(h.line_length, h.visible_length), light_point);
}

double LineSolidAngleStrategy::pdf(const Vec3& light_point) const {
  if (!family_) return 0;
  Vec2 st = family_->coordinates(light_point);
  if (!(st.x >= 0 && st.x <= 1 && st.y >= 0 && st.y <= 1)) return 0;
  TracedLine line;
  family_->trace(st.x, *query_, line);
  return pdf(line, st.y, light_point);
}

}  // namespace penumbra

namespace penumbra {

std::optional<std::string> LineSolidAngleStrategy::refusal(const Scene& scene,
                                                           LineDirection direction) {
  if (auto why = edge_direction_only(name(), direction)) return why;
  if (auto why = first_light_not_quad(
          scene, "strategy \"line-sa\" samples lines of quad lights (along edge1 or edge2)"))
    return why;
  for (size_t l = 0; l < scene.lights.size(); ++l)
    if (!supports(scene.lights[l]))
      return "strategy \"line-sa\" needs a rectangular light (Ureña et al.'s spherical "
             "rectangle); light " +
             std::to_string(l) +
             " is a parallelogram whose edges are not perpendicular (to 1e-6 relative): use "
             "line-area";
  return std::nullopt;
}

}  // namespace penumbra
