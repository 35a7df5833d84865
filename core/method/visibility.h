#pragma once
// What the estimator asks of the scene's geometry: shadow rays and, for line strategies, the
// shadow-triangle query. core/render implements it with Embree and core/lines.

#include "core/math/vec.h"

namespace penumbra {

class LineQuery;

class Visibility {
 public:
  virtual ~Visibility() = default;
  // True when an occluder blocks the segment from `from` (on a surface with unit normal `normal`
  // facing the segment) to `to` (a point on a light).
  virtual bool occluded(const Vec3& from, const Vec3& normal, const Vec3& to) const = 0;
  // The shadow-triangle query over the same occluders (core/lines/line_query.h), needed by
  // methods with line terms; null when the implementation has none.
  virtual const LineQuery* line_query() const { return nullptr; }
};

}  // namespace penumbra
