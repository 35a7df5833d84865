#pragma once
// `line-bd16`: Billen & Dutré 2016's analytic line samples (core/lines/bd16_estimator.h) as a
// strategy of the registry. Each sample is a whole line integrated in closed form, so the
// strategy has no density at a point: it cannot take part in MIS (the method check allows it
// alone or with /avg). `:u` and `:v` follow the light's edges; `:rand` draws one direction per
// shading point.
//
// Parameters: the line direction of the term. Samples: n offsets stratified in 1D by the
// method's sampler, and the direction's two numbers from a counter no pattern sample uses.

#include <optional>
#include <string>
#include <string_view>

#include "core/lines/bd16_estimator.h"
#include "core/sampling/pattern.h"
#include "core/strategies/registry.h"
#include "core/strategies/strategy.h"

namespace penumbra {

class LineBd16Strategy {
 public:
  static constexpr std::string_view name() { return "line-bd16"; }
  static constexpr StrategyFamily kFamily = StrategyFamily::AnalyticLine;
  static constexpr bool kRectangleStrata = false;
  // Disk lights, gaussian profiles and materials other than lambert and phong (the closed forms).
  static std::optional<std::string> refusal(const Scene& scene, LineDirection direction);

  // The light and the shading point's material must be supported (refusal() is empty).
  LineBd16Strategy(const ShadingPoint& sp, const Light& light, LineDirection direction);

  // The sum of n line estimates (each integral / p(offset)) for the shading point's streams;
  // the estimator divides by n.
  Rgb estimate_sum(Pattern pattern, const StreamKey& stream, int n, const LineQuery& query) const;

 private:
  Bd16LineSampler sampler_;
};

}  // namespace penumbra
