#include "core/lines/line_sampling_lines.h"

#include <algorithm>
#include <cmath>

namespace penumbra {

std::optional<QuadLineFamily> QuadLineFamily::prepare(const Vec3& x, const Vec3& normal,
                                                      const Light& light, LineAxis axis) {
  if (light.type != LightType::Quad) return std::nullopt;
  QuadLineFamily family;
  family.x_ = x;
  family.normal_ = normal;
  family.axis_ = axis;
  family.origin_ = light.origin;
  family.along_ = axis == LineAxis::Edge1 ? light.edge1 : light.edge2;
  family.across_ = axis == LineAxis::Edge1 ? light.edge2 : light.edge1;
  family.along_length_ = length(family.along_);
  family.across_length_ = length(family.across_);
  family.plane_normal_ = cross(family.along_, family.across_);
  family.plane_normal_sq_ = length_squared(family.plane_normal_);
  if (!(family.along_length_ > 0) || !(family.across_length_ > 0) ||
      !(family.plane_normal_sq_ > 0) || !std::isfinite(family.plane_normal_sq_))
    return std::nullopt;
  return family;
}

void QuadLineFamily::trace(double offset, const LineQuery& query, TracedLine& out) const {
  out.offset = offset;
  Vec3 start = origin_ + offset * across_;
  // Height above the tangent plane along the line: g(t) = g0 + t (g1 - g0), linear in t.
  double g0 = dot(normal_, start - x_);
  double g1 = g0 + dot(normal_, along_);
  double lo = 0, hi = 1;
  if (!(g0 > 0) && !(g1 > 0)) {
    lo = hi = 0;
  } else if (!(g0 > 0) || !(g1 > 0)) {
    double crossing = std::clamp(g0 / (g0 - g1), 0.0, 1.0);
    if (g0 > 0) {
      hi = crossing;
    } else {
      lo = crossing;
    }
  }
  out.horizon_lo = lo;
  out.horizon_hi = hi;
  if (!(lo < hi)) {
    out.visible.clear();
    return;
  }
  if (lo == 0 && hi == 1) {
    query.visible_intervals(x_, start, start + along_, out.visible);
    return;
  }
  // Query only the part above the horizon, then map its parameter back to the whole line.
  thread_local IntervalList clipped;
  query.visible_intervals(x_, start + lo * along_, start + hi * along_, clipped);
  double span = hi - lo;
  out.visible.reset(lo, hi);
  if (clipped.empty()) {
    out.visible.clear();
    return;
  }
  double previous = lo;
  for (const Interval& piece : clipped) {
    double piece_lo = lo + piece.lo * span, piece_hi = lo + piece.hi * span;
    out.visible.subtract(previous, piece_lo);
    previous = piece_hi;
  }
  out.visible.subtract(previous, hi);
}

Vec2 QuadLineFamily::coordinates(const Vec3& point) const {
  // The dual basis of (along, across) within the light's plane.
  Vec3 d = point - origin_;
  double t = dot(cross(d, across_), plane_normal_) / plane_normal_sq_;
  double offset = dot(cross(along_, d), plane_normal_) / plane_normal_sq_;
  return {offset, t};
}

}  // namespace penumbra
