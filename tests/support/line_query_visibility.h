#pragma once
// Visibility by a LineQuery alone: its shadow rays for the point terms and the query itself for
// the line terms, so a test needs no Embree scene for its occluders.

#include "core/lines/line_query.h"
#include "core/method/visibility.h"

namespace penumbra::testing {

class LineQueryVisibility : public Visibility {
 public:
  explicit LineQueryVisibility(const LineQuery& query) : query_(query) {}
  bool occluded(const Vec3& from, const Vec3&, const Vec3& to) const override {
    return query_.occluded(from, to);
  }
  const LineQuery* line_query() const override { return &query_; }

 private:
  const LineQuery& query_;
};

}  // namespace penumbra::testing
