#pragma once
// The lines of a parallelogram light along one of its edges, as seen from a shading point
// (Salesin & Jarosz 2019 Sec. 4, Fig. 2): the line at offset s in [0,1] runs from
// origin + s * across to origin + s * across + along. Shared by the surface-area and the
// solid-angle line strategies (the line through a point along an edge is the same segment for
// both), and by the smoothing heuristic, which needs the visible region a point lies in.
//
// A traced line keeps its visible intervals in the parameter t in [0,1] of the whole line:
// the shadow-triangle query's visible intervals, clipped at the shading point's horizon (the
// part of the line below the tangent plane gets no samples and counts as not visible).

#include <optional>

#include "core/lines/intervals.h"
#include "core/lines/line_query.h"
#include "core/math/vec.h"
#include "core/scene/scene.h"

namespace penumbra {

// The edge the lines run along: `u` lines run along edge1, `v` lines along edge2.
enum class LineAxis { Edge1, Edge2 };

struct TracedLine {
  double offset = 0;      // s in [0,1]
  double horizon_lo = 0;  // the part of the line above the horizon: t in [horizon_lo,
  double horizon_hi = 1;  // horizon_hi] (empty when lo >= hi)
  IntervalList visible;   // visible and above the horizon, in t of the whole line
};

class QuadLineFamily {
 public:
  // Empty when the light is not a quad or has a degenerate edge.
  static std::optional<QuadLineFamily> prepare(const Vec3& x, const Vec3& normal,
                                               const Light& light, LineAxis axis);

  // The visible intervals of the line at `offset` (one shadow-triangle query, on the part
  // above the horizon only; no query when nothing of the line is above it).
  void trace(double offset, const LineQuery& query, TracedLine& out) const;

  // (offset, t) of a point of the light's plane: the line through it and where on that line.
  Vec2 coordinates(const Vec3& point) const;
  Vec3 point_at(double offset, double t) const { return origin_ + offset * across_ + t * along_; }

  double along_length() const { return along_length_; }
  double across_length() const { return across_length_; }
  LineAxis axis() const { return axis_; }

 private:
  Vec3 x_, normal_;
  Vec3 origin_, along_, across_;
  double along_length_ = 0, across_length_ = 0;
  Vec3 plane_normal_;           // along x across
  double plane_normal_sq_ = 0;  // |along x across|^2
  LineAxis axis_ = LineAxis::Edge1;
};

// Which visible piece of `line` contains t (index into line.visible), or -1.
inline int visible_piece_containing(const TracedLine& line, double t) {
  for (size_t i = 0; i < line.visible.size(); ++i)
    if (line.visible[i].lo <= t && t <= line.visible[i].hi) return int(i);
  return -1;
}

}  // namespace penumbra
